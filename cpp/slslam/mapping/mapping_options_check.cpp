// Range checks of the local-mapping options (triangulation, local mapper), kept apart from the
// algorithms so that a new option and its bound are read together.
#include "slslam/core/check.h"
#include "slslam/mapping/local_mapper.h"
#include "slslam/mapping/triangulation.h"

namespace slslam {

void TriangulationOptions::Check() const {
  CheckInRange("triangulation.neighbours", neighbours, 0, 10000);
  CheckAboveInRange("triangulation.epipolar_px", epipolar_px, 0.0, limits::kMaxImageDistancePx);
  CheckAboveInRange("triangulation.max_distance_binary", max_distance_binary, 0.0f, 256.0f);
  CheckAboveInRange("triangulation.max_distance_float", max_distance_float, 0.0f,
                    limits::kMaxDescriptorDistance);
  CheckAboveInRange("triangulation.ratio", ratio, 0.0f, 1.0f);
  CheckInRange("triangulation.min_parallax_deg", min_parallax_deg, 0.0, 180.0);
  CheckInRange("triangulation.patch_window_px", patch_window_px, 0, 50);
  CheckAboveInRange("triangulation.max_depth_baselines", max_depth_baselines, 0.0, 1e6);
  CheckAboveInRange("triangulation.chi2", chi2, 0.0, 1e6);
  CheckAboveInRange("triangulation.sigma_px", sigma_px, 0.0, 1e4);
  CheckAboveInRange("triangulation.line_sigma_px", line_sigma_px, 0.0, 1e4);
  CheckAboveInRange("triangulation.line_max_lbd", line_max_lbd, 0.0f, limits::kLbdBits);
  CheckAboveInRange("triangulation.line_ratio", line_ratio, 0.0f, 1.0f);
  CheckInRange("triangulation.min_plane_angle_deg", min_plane_angle_deg, 0.0, 90.0);
}

void LocalMapperOptions::Check() const {
  CheckInRange("mapping.local_keyframes", local_keyframes, 1, 10000);
  CheckInRange("mapping.max_fixed_keyframes", max_fixed_keyframes, 0, 10000);
  CheckAboveInRange("mapping.redundant_ratio", redundant_ratio, 0.0, 1.0);
  CheckInRange("mapping.redundant_observers", redundant_observers, 1, 1000);
  CheckInRange("mapping.min_found_ratio", min_found_ratio, 0.0, 1.0);
  CheckAboveInRange("mapping.point_sigma_px", point_sigma_px, 0.0, 1e4);
  CheckAboveInRange("mapping.line_sigma_px", line_sigma_px, 0.0, 1e4);
  CheckInRange("tracking.imu.local_ba_keyframes", inertial_keyframes, 0, 1000);
  triangulation.Check();
  ba.Check();
}

}  // namespace slslam
