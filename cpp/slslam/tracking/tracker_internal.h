// Small helpers shared by the tracker's source files (tracker*.cpp); not part of the API.
#pragma once

#include <array>
#include <chrono>
#include <cmath>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slslam/core/pinhole_camera.h"
#include "slslam/core/rigid3.h"
#include "slslam/features/image_patch.h"
#include "slslam/features/stereo_frame.h"
#include "slslam/map/map.h"
#include "slslam/optimization/pose_optimizer.h"

namespace slslam::tracker_detail {

using Clock = std::chrono::steady_clock;

// Milliseconds since `since`.
inline double Ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

// One descriptor row of the same type and width as the rows of `rows`.
inline bool SameKind(const cv::Mat& descriptor, const cv::Mat& rows) {
  return descriptor.rows == 1 && descriptor.cols == rows.cols && descriptor.type() == rows.type();
}

inline bool InImage(const PinholeCamera& camera, const Eigen::Vector2d& uv, double margin = 0.0) {
  return uv.x() >= -margin && uv.y() >= -margin && uv.x() <= camera.width - 1 + margin &&
         uv.y() <= camera.height - 1 + margin;
}

// (u_left, v, u_right) of keypoint k as an observation: at `refined` when that is finite (the
// stereo column moved by as much as the keypoint, a keypoint without one keeps -1), else as
// detected.
inline Eigen::Vector3d ObservedPixel(const StereoFrame& frame, int k,
                                     const Eigen::Vector2f& refined) {
  const double u = frame.keypoints.uv(k, 0), v = frame.keypoints.uv(k, 1);
  const double u_right = frame.u_right[k];
  if (!std::isfinite(refined.x())) return {u, v, u_right};
  return {refined.x(), refined.y(), u_right >= 0.0 ? u_right + (refined.x() - u) : u_right};
}

// (features/image_patch.h: the patches are sampled by local mapping too)
using ::slslam::SampleGrid;
using ::slslam::SamplePatch;

// Aligns `patch` (SamplePatch's, w from its size) to `image` around (u, v), the patch spanning
// `scale` image pixels per patch pixel: Gauss-Newton on the zero-mean difference (a brightness
// offset between the two drops out), at most 10 steps. True with (u, v) moved to the alignment
// when it converged on texture (both eigenvalues of the normal matrix large enough) and the two
// patches correlate (zero-mean NCC >= min_ncc).
bool AlignPatch(const cv::Mat& image, const cv::Mat& patch, double scale, double min_ncc, double* u,
                double* v);

// The offset (even integers within +-radius_px) of (u, v) where `patch` (SamplePatch's)
// correlates best with `image` (zero-mean NCC on every other patch pixel, the patch spanning
// `scale` image pixels per patch pixel): (u, v) moved there, the NCC returned (-1 when no offset
// fits the image or the patch is flat). A coarse start for AlignPatch when the prediction may be
// further off than its reach (TrackerOptions::projected_max_frames).
double SearchPatch(const cv::Mat& image, const cv::Mat& patch, double scale, int radius_px,
                   double* u, double* v);

// Extends the display endpoints of `line` (world frame) to the segment `seg` observed by the camera
// at `cam_from_world` (the points of the line nearest to the segment's endpoint rays, up to
// max_depth_m deep), so that a long edge the camera drives along stays in front of it as a map
// line.
void ExtendToSegment(const PinholeCamera& camera, const Rigid3d& cam_from_world,
                     const LineSegment& seg, double max_depth_m, MapLine* line);

// Lines within this angle of their mean direction count as parallel [rad]: the pose they give
// has no information along them (two nearly parallel map lines whose directions differ by their
// triangulation errors would turn a lateral offset into a false one along them).
constexpr double kParallelLinesMaxRad = 0.2;

// The mean world direction of the inlier lines (unit) when every one is within
// kParallelLinesMaxRad of it, else zero.
Eigen::Vector3d SharedDirection(const std::vector<LineObservation>& lines,
                                const std::vector<bool>& inlier);

// The part of `seg` inside the image; false when none is.
bool ClipToImage(const PinholeCamera& camera, LineSegment* seg);

// Adds a keyframe's stereo endpoints of a segment of `line` (camera frame; world_from_cam the
// keyframe's pose) to its support, each weighted by 1 / depth^2 (stereo's depth error grows with
// depth squared; the weight is milder than its inverse variance, as the far end is also where
// the segment's endpoint is least sharp).
void AddStereoSupport(const Rigid3d& world_from_cam,
                      const std::array<Eigen::Vector3d, 2>& endpoints_cam, MapLine* line);

// Refits `line` to its support (weighted total least squares: through the weighted centroid,
// along the principal direction), its display endpoints moved onto the fit.
void RefitToSupport(MapLine* line);

// Nearest depth of a map line's part that tracking projects [m].
constexpr double kMinLineDepthM = 0.1;

// The part of the world segment (start_w, end_w) in front of the camera at `cam_from_world` (depth
// at least min_depth_m), in the camera frame; false when none is.
bool ClipToFront(const Rigid3d& cam_from_world, const Eigen::Vector3d& start_w,
                 const Eigen::Vector3d& end_w, double min_depth_m, Eigen::Vector3d* start_c,
                 Eigen::Vector3d* end_c);

}  // namespace slslam::tracker_detail
