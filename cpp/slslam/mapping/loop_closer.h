// Loop closing and map merging (ORB-SLAM3's LoopClosing thread, of the architecture the SL-SLAM
// paper builds on), for a stereo point-line map.
//
// For every keyframe local mapping has finished:
//  1. Candidates: keyframes of every map of the atlas whose bag of words scores at least as high
//     as the new keyframe's weakest covisible neighbour, excluding its covisible keyframes.
//  2. Geometric verification: the keyframe's keypoints matched to the candidate's map points
//     within shared vocabulary nodes, EPnP RANSAC, then the candidate's local map (points AND
//     lines) projected and optimised by the caller's local-map tracker (`LocalMapVerifier`).
//  3. Plausibility (same map): the correction must be explainable by drift, at most
//     `max_correction_ratio` of the path driven since the candidate (plus a floor). Mine roadways
//     repeat (arches, mesh, bolts): an aliased match gives a confident but wrong transform, and a
//     false loop is worse than a missed one.
//  4. Consistency: `consistency` consecutive keyframes must verify against the same map with
//     transforms that agree.
//  5. Same map, a loop: the keyframe and its neighbours take the verified pose, duplicated points
//     and lines are fused, the essential graph (spanning tree, strong covisibility, loop edges)
//     is optimised in Ceres, every landmark follows its reference keyframe, then global bundle
//     adjustment over points and lines.
//     Another map, a merge: the active map is transformed into the older one and absorbed, then
//     the same fusion, graph and bundle adjustment weld the two.
//  6. Global BA runs inline in sequential mode (reproducible) and in the background otherwise:
//     built under the map's lock, solved on its own thread without the lock while tracking and
//     local mapping go on, written back under the lock, with what they added meanwhile carried
//     along by the correction of its nearest keyframe (ORB-SLAM3's RunGlobalBundleAdjustment).
//     A new loop or merge cancels a run in flight (its result would be in a stale world).
#pragma once

#include <atomic>
#include <exception>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <thread>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"
#include "slslam/mapping/atlas.h"
#include "slslam/optimization/bundle_adjustment.h"
#include "slslam/optimization/pose_graph.h"
#include "slslam/place/vocabulary.h"

namespace slslam {

// The alignment closest to `target_from_source` that maps gravity's direction in the source world
// (g_source) onto the target's (g_target): the rotation corrected by the least rotation that
// brings R g_source onto g_target (a turn about gravity and a translation remain, the degrees of
// freedom a visual-inertial map leaves open), the translation such that `pivot_source` (a
// source-world point: the merging keyframe's centre) lands where target_from_source put it.
Rigid3d YawAndPositionAlignment(const Rigid3d& target_from_source, const Eigen::Vector3d& g_source,
                                const Eigen::Vector3d& g_target,
                                const Eigen::Vector3d& pivot_source);

struct LoopClosingOptions {
  bool enabled = true;                  ///< detect and close loops within a map
  bool merge_maps = true;               ///< detect links to other maps of the atlas and merge
  int min_keyframes = 12;               ///< a map needs this many keyframes before loops [-]
  int candidates = 3;                   ///< best BoW candidates verified per keyframe [-]
  int min_matches = 20;                 ///< word matches a candidate needs for PnP [-]
  float match_ratio = 0.75f;            ///< best / second best within a vocabulary node [-]
  double ransac_error_px = 3.0;         ///< PnP RANSAC inlier bound [px]
  int ransac_iterations = 300;          ///< [-]
  int min_pnp_inliers = 20;             ///< [-]
  double min_inliers = 80.0;            ///< weighted inliers of the candidate's local map [-]
  int consistency = 3;                  ///< consecutive verified keyframes that must agree [-]
  double agree_m = 0.3;                 ///< consecutive transforms agree within this [m]
  double agree_rad = 0.05;              ///< ... and this [rad]
  double max_correction_ratio = 0.05;   ///< same map: correction / path since the candidate [-]
  double max_correction_floor_m = 0.5;  ///< same map: correction always allowed [m]
  double max_correction_rad = 0.3;      ///< same map: largest rotation correction [rad]
  int strong_covisibility = 100;  ///< shared points for an essential-graph covisibility edge [-]
  bool global_ba = true;          ///< global bundle adjustment after a loop or merge
  /// Welding BA after a merge (ORB-SLAM3's): the merged keyframe and the candidate, each with
  /// this many of its best covisible keyframes, with the points and lines they see; the older
  /// map's keyframes and the landmarks' other observers fixed, the merged map's side free. It
  /// makes the seam consistent before a background global BA, or without one; sequential mode
  /// with global_ba skips it (the inline global BA follows at once) [-]; 0: no welding BA
  int welding_keyframes = 10;
  int vocabulary_levels_up = 2;  ///< direct-index level of the keyframes' words
  double point_sigma_px = 1.0;   ///< global BA point sigma [px] (the tracker sets its own)
  double line_sigma_px = 3.0;    ///< global BA line sigma [px]
  PoseGraphOptions pose_graph;
  /// A map whose gravity the IMU gave (Map::gravity_direction) corrects a loop in yaw and
  /// position only (the pose graph's 4-DoF mode, as ORB-SLAM3's visual-inertial mode): roll and
  /// pitch are observable there, and a loop's error in them is the camera's, not the IMU's. A
  /// merge of two such maps turns the merged one about gravity only (YawAndPositionAlignment).
  bool yaw_and_position_with_gravity = true;
  BundleAdjustmentOptions global_ba_options;

  void Check() const;
};

struct LoopClosingStats {
  int keyframes_checked = 0;
  int candidates_verified = 0;         ///< candidates that passed geometric verification
  int loops_detected = 0;              ///< verified and plausible hypotheses (before consistency)
  int loops_rejected = 0;              ///< verified but implausible (drift gate) or inconsistent
  int loops_accepted = 0;              ///< loops closed within a map
  int merges = 0;                      ///< maps merged into an older one
  int merges_in_yaw_and_position = 0;  ///< of which aligned about gravity only (both had it)
  int global_ba_runs = 0;              ///< finished global BAs (not counting cancelled ones)
  int global_ba_cancelled = 0;         ///< background global BAs a newer loop or merge cancelled
  double loop_ms = 0.0;                ///< detection + verification + correction [ms]
  double global_ba_ms = 0.0;           ///< build + solve + write back of the finished runs [ms]
  double global_ba_lock_ms = 0.0;  ///< of which the map's lock was held (build, write back) [ms]
  int welding_ba_runs = 0;         ///< welding BAs after merges
  double welding_ba_ms = 0.0;      ///< their build + solve + write back [ms]
};

// What the tracker found when tracking the candidate's local map in the keyframe's frame from a
// pose: the optimised pose and the inlier matches. The caller holds the map's mutex.
struct LocalMapMatch {
  bool success = false;
  Rigid3d cam_from_world;  ///< the optimised pose, world (of the map) -> camera
  double weighted_inliers = 0.0;
  std::vector<int> point_ids, keypoints;  ///< inlier pairs (map point, keypoint of the frame)
  std::vector<int> line_ids, segments;    ///< inlier pairs (map line, segment of the frame)
};
using LocalMapVerifier = std::function<LocalMapMatch(
    const StereoFrame& frame, Map& map, int reference_keyframe, const Rigid3d& cam_from_world)>;

// One keyframe's keypoints matched to a keyframe's map points within shared vocabulary nodes
// (one-to-one, ratio test): (keypoint, map point id) pairs. Caller holds the map's mutex.
std::vector<std::pair<int, int>> MatchByWords(const cv::Mat& descriptors,
                                              const FeatureVector& features, const KeyFrame& kf,
                                              const Map& map, float max_distance, float ratio)
    SLSLAM_REQUIRES(map.mutex());

// The camera pose cam_from_world from (keypoint, map point id) matches: EPnP RANSAC on the
// keypoints' left pixels. False when RANSAC fails, keeps fewer than `min_inliers`, or the pose is
// not finite. Caller holds the map's mutex.
bool PoseFromMatches(const StereoFrame& frame, const Map& map,
                     const std::vector<std::pair<int, int>>& matches, const PinholeCamera& camera,
                     int iterations, double error_px, int min_inliers, Rigid3d* cam_from_world)
    SLSLAM_REQUIRES(map.mutex());

// One accepted loop or merge: the keyframe that closed it and the older keyframe it matched, by
// the frames they were made from (so a benchmark can check both against ground truth).
struct LoopEvent {
  int keyframe_id = -1;
  int candidate_id = -1;
  int frame_index = -1;            ///< input frame of the keyframe
  int candidate_frame_index = -1;  ///< input frame of the matched older keyframe
  bool merge = false;              ///< maps merged (else a loop within a map)
  double correction_m = 0.0;       ///< how far the keyframe moved [m]
};

class LoopCloser {
 public:
  // `background_global_ba`: global BA on its own thread (threaded mode) instead of inline.
  LoopCloser(const StereoRig& rig, const LoopClosingOptions& options, const Vocabulary* vocabulary,
             float max_descriptor_distance_binary, float max_descriptor_distance_float,
             LocalMapVerifier verifier, bool background_global_ba = false);
  ~LoopCloser();  // cancels and joins a global BA in flight
  LoopCloser(const LoopCloser&) = delete;
  LoopCloser& operator=(const LoopCloser&) = delete;

  // Looks for a loop or a merge for a keyframe local mapping has processed, and closes it.
  // Returns true when the atlas changed (a loop was corrected or maps were merged).
  bool Process(Atlas* atlas, int map_index, int keyframe_id);
  LoopClosingStats stats() const;
  std::vector<LoopEvent> events() const;
  // Waits until a global BA running in the background has been written back (end of a run,
  // before saving or exporting the map). No-op inline.
  void WaitForGlobalBa();

 private:
  struct Verified {
    int target_map = -1;
    int candidate = -1;
    LocalMapMatch match;         ///< K in the target map's world
    Rigid3d target_from_source;  ///< source map's world -> target map's world
  };
  struct Pending {
    int target_map = -1;
    int count = 0;
    int misses = 0;
    Rigid3d target_from_source;  ///< of the latest verified hypothesis
  };
  struct LoopEdge {
    int a = -1, b = -1;  ///< keyframe ids
    Rigid3d a_from_b;
  };

  bool Verify(Atlas* atlas, int source_map, const KeyFrame& kf, int target_map, int candidate,
              Verified* out);
  // Process's steps. The place-recognition candidates of `kf` (keyframe database queries in
  // every map that may take it), best first: (-score, map, keyframe id).
  std::vector<std::tuple<double, int, int>> Candidates(Atlas* atlas, int source, const KeyFrame& kf,
                                                       const std::set<int>& exclude,
                                                       double min_score, int map_keyframes) const;
  // The first candidate that passes Verify (into `out`); false when none does.
  bool VerifyFirst(Atlas* atlas, int source, const KeyFrame& kf,
                   const std::vector<std::tuple<double, int, int>>& candidates, Verified* out);
  // Updates the source map's pending hypothesis with this keyframe's result (`found`,
  // `verified`); true when it has been confirmed often enough to be applied.
  bool Consistent(int source, bool found, const Verified& verified);
  // Applies a confirmed loop (a correction of the source map) or merge (into the target map);
  // the map corrected, or -1 when the keyframe went meanwhile.
  int Apply(Atlas* atlas, int source, int keyframe_id, const KeyFrame& kf,
            const Verified& verified);
  // Path length along the keyframes (by id) between two keyframes of a map [m]. Caller locks.
  static double PathLength(const Map& map, int from_id, int to_id) SLSLAM_REQUIRES(map.mutex());
  // Moves every keyframe, point and line of `map` from the source world into the target world
  // (caller locks).
  static void TransformMap(Map* map, const Rigid3d& target_from_source)
      SLSLAM_REQUIRES(map->mutex());
  // Fusion, essential graph and global BA in `map` after K got its verified pose. Caller locks.
  void Correct(Map* map, int keyframe_id, const Verified& verified) SLSLAM_REQUIRES(map->mutex());
  void Fuse(Map* map, int keyframe_id, const LocalMapMatch& match) SLSLAM_REQUIRES(map->mutex());
  // Global BA over every keyframe, point and line of the atlas's map `map_index` (see 6. above).
  // After a merge, under the map's lock: local BA over the two sides of the seam (see
  // LoopClosingOptions::welding_keyframes), inline; `merged_side` holds the keyframes of the map
  // just merged (free), the others are fixed.
  void WeldingBundleAdjustment(Map* map, int keyframe_id, int candidate_id,
                               const std::set<int>& merged_side) SLSLAM_REQUIRES(map->mutex());
  void GlobalBundleAdjustment(Atlas* atlas, int map_index);
  void CancelGlobalBa();

  StereoRig rig_;
  LoopClosingOptions options_;
  const Vocabulary* vocabulary_;
  float max_distance_binary_, max_distance_float_;
  LocalMapVerifier verifier_;
  std::map<int, Pending> pending_;                   ///< per source map
  std::map<int, std::vector<LoopEdge>> loop_edges_;  ///< per map, kept for later graphs
  std::map<int, int> corrected_before_;  ///< per map: keyframe ids below this predate its last
                                         ///< correction (no loop search for them)
  mutable std::mutex stats_mutex_;
  LoopClosingStats stats_;
  std::vector<LoopEvent> events_;
  bool background_global_ba_ = false;
  std::thread global_ba_thread_;
  std::atomic<bool> global_ba_abort_{false};
  std::exception_ptr global_ba_error_;  ///< from the background thread, joined before read
};

}  // namespace slslam
