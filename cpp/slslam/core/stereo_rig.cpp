#include "slslam/core/stereo_rig.h"

#include "slslam/core/check.h"

namespace slslam {

void StereoRig::Check() const {
  camera.Check();
  SLSLAM_CHECK(baseline_m > 0.0 && baseline_m <= 1000.0,
               "stereo baseline must be in (0, 1000] m, got ", baseline_m, " m");
}

}  // namespace slslam
