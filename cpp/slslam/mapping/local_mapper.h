// Local mapping (SL-SLAM paper): for every new keyframe, new points and lines triangulated with its
// covisible keyframes (triangulation.h), local bundle adjustment over the keyframe and
// its covisible keyframes with the points and lines they see (keyframes outside that set that see
// those landmarks stay fixed), removal of outlier observations, landmark culling and keyframe
// culling (a keyframe is redundant when > 90 % of its map points are seen by >= 3 other
// keyframes). Runs inline (sequential mode, exactly reproducible) or on a background thread as in
// ORB-SLAM3. Sequential mode can overlap each keyframe's local BA with tracking and still be
// exactly reproducible: the solve runs on a thread of its own, on the window's copy of the map,
// and its result is applied when the next keyframe comes (or at Flush), whatever its timing.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

#include "slslam/map/map.h"
#include "slslam/mapping/map_bundle_adjustment.h"
#include "slslam/mapping/triangulation.h"
#include "slslam/optimization/bundle_adjustment.h"

namespace slslam {

struct LocalMapperOptions {
  int local_keyframes = 10;       ///< covisible keyframes optimised with the new one [-]
  int max_fixed_keyframes = 10;   ///< fixed keyframes that anchor the local window [-]
  double redundant_ratio = 0.9;   ///< keyframe culling: share of points seen by enough others [-]
  int redundant_observers = 3;    ///< keyframe culling: other keyframes that must see a point [-]
  double min_found_ratio = 0.25;  ///< point culling: found / visible below this removes it [-]
  bool cull_keyframes = true;
  bool triangulate = true;  ///< new points and lines from covisible keyframe pairs
  TriangulationOptions triangulation;
  double point_sigma_px = 1.0;  ///< [px]
  double line_sigma_px = 3.0;   ///< [px]
  /// With a map that has an IMU (Map::inertial): the last this many keyframes of the IMU chain
  /// join the window, with the IMU factors between consecutive ones (velocity and biases
  /// estimated); 0: none. Set by the tracker from tracking.imu.local_ba_keyframes [-]
  int inertial_keyframes = 0;
  BundleAdjustmentOptions ba;

  void Check() const;  ///< mapping_options_check.cpp
};

struct LocalMappingStats {
  int keyframes_processed = 0;
  int keyframes_culled = 0;
  int points_culled = 0;
  int lines_culled = 0;
  int points_triangulated = 0;
  int lines_triangulated = 0;
  double total_ba_ms = 0.0;     ///< local mapping's time, all steps [ms]
  int ba_interrupted = 0;       ///< local BAs stopped early by InterruptBA (threaded mode)
  double ba_solve_ms = 0.0;     ///< of total_ba_ms, the local BAs' solves (Ceres) [ms]
  int ba_iterations = 0;        ///< the local BAs' trust-region steps, both passes [-]
  int ba_rejected_steps = 0;    ///< of which rejected (BundleAdjustmentReport) [-]
  int ba_inertial_factors = 0;  ///< IMU factors between keyframes, all local BAs [-]
};

class LocalMapper {
 public:
  // `overlap` (sequential mode only): keyframe k's triangulation and window are made inline; its
  // local BA solves on a thread of its own while tracking goes on; the solution is applied, and
  // the landmarks and keyframes culled, when keyframe k+1 is inserted or at Flush. The frames in
  // between are tracked against the map as it was before that BA.
  LocalMapper(const StereoRig& rig, const LocalMapperOptions& options, bool sequential,
              bool overlap = false);
  ~LocalMapper();
  LocalMapper(const LocalMapper&) = delete;
  LocalMapper& operator=(const LocalMapper&) = delete;

  // Queues (threaded) or processes at once (sequential; with overlap, the previous keyframe's
  // solve is applied first and this one's starts) a new keyframe of `map`. The map must outlive
  // the processing (Flush before destroying it).
  void Insert(Map* map, int keyframe_id);
  // Waits until every queued keyframe has been processed (with overlap: the pending solve has
  // been applied); rethrows the first error the mapping thread caught since the last Flush.
  void Flush();
  LocalMappingStats stats() const;
  // Threaded mode (ORB-SLAM3's brake on keyframe insertion): true when no keyframe is queued or
  // being processed; always true in sequential mode.
  bool Idle() const;
  // Keyframes waiting in the queue, not counting the one being processed (0 when sequential).
  int QueuedKeyFrames() const;
  // Threaded mode: the local BA running now (if any) stops after its current iteration and keeps
  // the estimate it has reached (ORB-SLAM3's InterruptBA, when tracking inserts a keyframe while
  // mapping is busy: the newer keyframe's window starts sooner). No effect in sequential mode.
  void InterruptBA() {
    if (!sequential_) interrupt_ba_.store(true);
  }
  // Called (on the mapping thread, or inline in sequential mode) after each keyframe has been
  // processed, without any lock held: loop closing runs there, serialised with local mapping.
  void SetAfterKeyFrame(std::function<void(Map*, int)> hook) { after_keyframe_ = std::move(hook); }

 private:
  // One keyframe's local mapping between its steps.
  struct Window {
    Map* map = nullptr;
    int keyframe_id = -1;
    MapBundleAdjustment ba;
    TriangulationStats triangulated;
    BundleAdjustmentReport report;
    double ms = 0.0;        ///< the steps' own time so far [ms]
    double solve_ms = 0.0;  ///< of which the solve [ms]
    std::exception_ptr error;
    std::thread solver;
  };
  void Process(Map* map, int keyframe_id);
  bool Prepare(Window* window);  ///< triangulation, the window's problem; false: no keyframe
  void Solve(Window* window);    ///< the local BA, without the map lock
  void Finish(Window* window);   ///< the solution applied, culling, statistics
  void FinishPending();
  void Run();

  StereoRig rig_;
  LocalMapperOptions options_;
  bool sequential_;
  bool overlap_ = false;
  std::unique_ptr<Window> pending_;
  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::condition_variable idle_cv_;
  std::deque<std::pair<Map*, int>> queue_;
  bool busy_ = false;
  bool stop_ = false;
  std::exception_ptr error_;
  std::atomic<bool> interrupt_ba_{false};
  std::function<void(Map*, int)> after_keyframe_;
  LocalMappingStats stats_;
  std::thread worker_;
};

}  // namespace slslam
