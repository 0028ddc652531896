#include "slslam/features/stereo_frame.h"

namespace slslam {

Eigen::Vector3d StereoFrame::Backproject(const PinholeCamera& camera, int i) const {
  return depth[i] * camera.Unproject(keypoints.uv.row(i).cast<double>().transpose());
}

}  // namespace slslam
