// A rectified stereo pair: the cameras every layer above core shares.
#pragma once

#include "slslam/core/pinhole_camera.h"

namespace slslam {

// Stereo rig of two rectified pinhole cameras with the same intrinsics; the right camera sits at
// +baseline along the left camera's x axis (u_right = u_left - fx * baseline / z).
struct StereoRig {
  PinholeCamera camera;
  double baseline_m = 0.0;  ///< [m]

  void Check() const;
};

}  // namespace slslam
