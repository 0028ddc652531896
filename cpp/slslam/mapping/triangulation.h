// New landmarks from pairs of keyframes (the SL-SLAM paper's local mapping, ORB-SLAM3's
// CreateNewMapPoints), run by local mapping for every new keyframe against its covisible
// keyframes. Stereo already gives the close keypoints and the non-horizontal segments a 3-D
// position when the keyframe is made; what is left is what one stereo pair cannot fix: keypoints
// without a stereo match (far, or seen by one camera) and segments along the epipolar lines
// (near-horizontal: roof edges, rails, cables). Two keyframes a motion apart can.
//
// Points: keypoints of both keyframes without a map point are paired along the epipolar line
// (distance to it, depth range, descriptor distance with a ratio test, one-to-one), triangulated
// linearly (DLT) and kept when they lie in front of both cameras, reproject within the chi-square
// bound and have enough parallax.
// Lines: segments of both keyframes without a map line are paired by LBD distance (mutual best
// with a ratio test); the 3-D line is the intersection of the two back-projected planes (the
// dual Pluecker matrix, geometry/plucker_line.h), kept when the planes are not near-parallel, the
// line lies in front of both cameras and its projection is within the chi-square bound of both
// observations.
#pragma once

#include <vector>

#include "slslam/core/rigid3.h"
#include "slslam/geometry/reprojection.h"
#include "slslam/map/map.h"

namespace slslam {

struct TriangulationOptions {
  int neighbours = 10;                ///< covisible keyframes paired with the new one [-]
  double epipolar_px = 2.0;           ///< largest distance to the epipolar line [px]
  float max_distance_binary = 50.0f;  ///< descriptor bound, ORB (Hamming) [bits]
  float max_distance_float = 0.7f;    ///< descriptor bound, SuperPoint (L2) [-]
  float ratio = 0.8f;                 ///< best / second best descriptor distance [-]
  /// Smallest angle between the two rays [deg]. 3, more than ORB-SLAM3's (about 1): the points
  /// that stereo left without depth, triangulated at 1-3 degrees, had poor depths, and in the
  /// dark dusty stretch of the 600-frame loops they pulled the poses; with 3 both ORB + lines and
  /// XFeat + lines drifted less on the four hard sequences (benchmarks/log/realtime.md)
  double min_parallax_deg = 3.0;
  double max_depth_baselines = 60.0;  ///< farther points are not made (stereo baselines) [-]
  double chi2 = 5.991;                ///< reprojection bound in both views (2 dof, 95 %) [-]
  double sigma_px = 1.0;              ///< keypoint sigma [px]
  double line_sigma_px = 3.0;         ///< line endpoint distance sigma [px]
  /// Points from keyframe pairs. What stereo leaves for them are the keypoints without a
  /// stereo match: flat, ambiguous along their row, or far; paired by descriptor and
  /// triangulated from the detected positions, with no patch to align later matches to
  /// (Tracker::RefineTracks). false: points come from stereo alone. At min_parallax_deg 1,
  /// without them XFeat + lines drifted less on the dark 600-frame sequences but more on the
  /// 150- and 300-frame dark loops; with min_parallax_deg 3 the points keep the short loops' gain
  /// without the long sequences' loss (benchmarks/log/realtime.md) [-]
  bool points = true;
  /// Half size of the patch a triangulated point keeps of the new keyframe's left image around
  /// its keypoint (KeyFrame::left_image), as the points the tracker makes from stereo keep one
  /// (MapPoint::patch, TrackerOptions::track_refine_window_px): later matches are aligned to it
  /// instead of taken at their detected positions. The tracker sets it
  /// (TrackerOptions::triangulated_point_patches) [px]; 0: no patch
  int patch_window_px = 0;
  bool lines = true;                 ///< also triangulate lines
  float line_max_lbd = 60.0f;        ///< LBD bound for line pairs [bits]
  float line_ratio = 0.8f;           ///< best / second best LBD distance [-]
  double min_plane_angle_deg = 2.0;  ///< smallest angle between the two planes [deg]

  void Check() const;
};

struct TriangulationStats {
  int points = 0;  ///< map points made
  int lines = 0;   ///< map lines made
};

// Linear two-view triangulation of the rays x1, x2 (normalised image coordinates, z = 1) seen
// from the poses cam1_from_world, cam2_from_world. False when the system is degenerate.
bool TriangulatePoint(const Rigid3d& cam1_from_world, const Eigen::Vector3d& x1,
                      const Rigid3d& cam2_from_world, const Eigen::Vector3d& x2,
                      Eigen::Vector3d* p_w);

namespace triangulation_detail {

// The free keypoints of one keyframe near an epipolar line of another, as a prefilter: the
// exhaustive scan's exact test (a division per pair, in a loop with a branch) was about 85 % of
// triangulation's time; the distances to the unit line come from one branch-free pass over the
// positions held side by side, and only the keypoints within the band go on to the exact test.
class EpipolarCandidates {
 public:
  // `ids`: the keypoints to consider (indices into `uv`), ascending.
  EpipolarCandidates(const Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>& uv,
                     const std::vector<int>& ids);

  // Replaces *out by the ids whose keypoint lies within `band_px` of the line
  // unit_line.x() u + unit_line.y() v + unit_line.z() = 0 ((x, y) of unit length), in ascending
  // order (the order of `ids`).
  void Collect(const Eigen::Vector3d& unit_line, double band_px, std::vector<int>* out);

 private:
  std::vector<int> ids_;          ///< the ids at finite positions
  std::vector<double> u_, v_;     ///< their positions [px]
  std::vector<double> distance_;  ///< scratch: distances to the current line [px]
};

}  // namespace triangulation_detail

// Pairs keyframe `keyframe_id` with its best covisible keyframes and adds the new landmarks to
// the map. The caller holds map.mutex().
TriangulationStats CreateNewLandmarks(Map* map, int keyframe_id, const StereoRig& rig,
                                      const TriangulationOptions& options = {})
    SLSLAM_REQUIRES(map->mutex());

}  // namespace slslam
