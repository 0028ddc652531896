#include "slslam/mapping/local_mapper.h"

#include <algorithm>
#include <chrono>
#include <exception>
#include <memory>
#include <set>
#include <unordered_map>

#include "slslam/core/time.h"
#include "slslam/mapping/map_bundle_adjustment.h"

namespace slslam {

LocalMapper::LocalMapper(const StereoRig& rig, const LocalMapperOptions& options, bool sequential,
                         bool overlap)
    : rig_(rig), options_(options), sequential_(sequential), overlap_(sequential && overlap) {
  options_.Check();
  if (!sequential_) worker_ = std::thread([this] { Run(); });
}

LocalMapper::~LocalMapper() {
  if (pending_ && pending_->solver.joinable()) pending_->solver.join();
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stop_ = true;
  }
  queue_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void LocalMapper::Insert(Map* map, int keyframe_id) {
  if (overlap_) {  // (sequential mode only: the constructor clears it otherwise)
    // The previous keyframe's solve is applied first: always here, whatever its timing.
    FinishPending();
    auto window = std::make_unique<Window>();
    window->map = map;
    window->keyframe_id = keyframe_id;
    if (Prepare(window.get())) {
      Window* w = window.get();
      w->solver = std::thread([this, w] {
        try {
          Solve(w);
        } catch (...) {  // rethrown by FinishPending on the caller's thread
          w->error = std::current_exception();
        }
      });
      pending_ = std::move(window);
    }
    if (after_keyframe_) after_keyframe_(map, keyframe_id);
    return;
  }
  if (sequential_) {
    Process(map, keyframe_id);
    if (after_keyframe_) after_keyframe_(map, keyframe_id);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    queue_.emplace_back(map, keyframe_id);
  }
  queue_cv_.notify_one();
}

void LocalMapper::Flush() {
  if (sequential_) {
    FinishPending();
    return;
  }
  std::unique_lock<std::mutex> lock(queue_mutex_);
  idle_cv_.wait(lock, [this] { return queue_.empty() && !busy_; });
  if (error_) {
    std::exception_ptr error = error_;
    error_ = nullptr;
    std::rethrow_exception(error);
  }
}

bool LocalMapper::Idle() const {
  if (sequential_) return true;
  std::lock_guard<std::mutex> lock(queue_mutex_);
  return queue_.empty() && !busy_;
}

int LocalMapper::QueuedKeyFrames() const {
  if (sequential_) return 0;
  std::lock_guard<std::mutex> lock(queue_mutex_);
  return static_cast<int>(queue_.size());
}

LocalMappingStats LocalMapper::stats() const {
  std::lock_guard<std::mutex> lock(queue_mutex_);
  return stats_;
}

void LocalMapper::Run() {
  while (true) {
    std::pair<Map*, int> job;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      queue_cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (stop_ && queue_.empty()) return;
      job = queue_.front();
      queue_.pop_front();
      busy_ = true;
    }
    std::exception_ptr error;
    try {
      Process(job.first, job.second);
      if (after_keyframe_) after_keyframe_(job.first, job.second);
    } catch (...) {  // a throw on this thread would terminate the process
      error = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      busy_ = false;
      if (error && !error_) error_ = error;
    }
    idle_cv_.notify_all();
  }
}

namespace {

// Culling `kf` would join two IMU intervals into one longer than the map's bound
// (MapInertial::max_interval_s): the chain would break there.
bool LongImuInterval(const Map& map, const KeyFrame& kf) SLSLAM_REQUIRES(map.mutex()) {
  if (!kf.inertial || !map.inertial()) return false;
  const double max_interval_s = map.inertial()->max_interval_s;
  auto previous = map.keyframe(kf.inertial->previous);
  if (!previous || !previous->inertial) return false;
  for (const auto& [id, other] : map.keyframes()) {
    (void)id;
    if (other->inertial && other->inertial->previous == kf.id) {
      return SecondsBetween(previous->inertial->t_ns, other->inertial->t_ns) > max_interval_s;
    }
  }
  return false;
}

}  // namespace

void LocalMapper::Process(Map* map, int keyframe_id) {
  Window window;
  window.map = map;
  window.keyframe_id = keyframe_id;
  if (!Prepare(&window)) return;
  Solve(&window);
  Finish(&window);
}

void LocalMapper::FinishPending() {
  if (!pending_) return;
  std::unique_ptr<Window> window = std::move(pending_);
  window->solver.join();
  if (window->error) std::rethrow_exception(window->error);
  Finish(window.get());
}

bool LocalMapper::Prepare(Window* window) {
  const auto start = std::chrono::steady_clock::now();
  Map* map = window->map;
  const int keyframe_id = window->keyframe_id;
  MapBundleAdjustment& ba = window->ba;
  {
    MutexLock lock(map->mutex());
    auto current = map->keyframe(keyframe_id);
    if (!current) return false;
    if (options_.triangulate) {
      window->triangulated = CreateNewLandmarks(map, keyframe_id, rig_, options_.triangulation);
      if (window->triangulated.points > 0) map->UpdateConnections(keyframe_id);
    }
    current->left_image.release();  // (its new points have their patches now)
    ba = MapBundleAdjustment(map->correction_epoch());
    std::vector<int> local = {keyframe_id};
    for (int id : map->BestCovisible(keyframe_id, options_.local_keyframes)) {
      if (map->keyframe(id)) local.push_back(id);
    }
    // With the IMU, the last keyframes of its chain too (a weak stretch's keyframes share few
    // points with each other: the covisible ones alone leave the chain in pieces), back to where
    // an interval is too long for a factor (beyond it, the two parts share nothing).
    const bool inertial = options_.inertial_keyframes > 0 && map->inertial().has_value();
    if (inertial) {
      auto kf = current;
      for (int n = 1; n < options_.inertial_keyframes && kf->inertial; ++n) {
        auto previous = map->keyframe(kf->inertial->previous);
        if (!previous || !previous->inertial ||
            !(SecondsBetween(previous->inertial->t_ns, kf->inertial->t_ns) <=
              map->inertial()->max_interval_s)) {
          break;
        }
        kf = previous;
        if (std::find(local.begin(), local.end(), kf->id) == local.end()) local.push_back(kf->id);
      }
    }
    std::unordered_map<int, int> pose_index;
    auto add_pose = [&](int kf_id, bool fixed) {
      map->mutex().AssertHeld();  // the lock above (a lambda is not followed by the analysis)
      pose_index[kf_id] = ba.AddPose(*map->keyframe(kf_id), fixed);
    };
    // The gauge: the map's first keyframe when it is in the window, else the window's oldest.
    const int first_keyframe = map->keyframes().begin()->first;
    const int anchor = std::find(local.begin(), local.end(), first_keyframe) != local.end()
                           ? first_keyframe
                           : *std::min_element(local.begin(), local.end());
    for (int id : local) add_pose(id, id == anchor || map->keyframe(id)->pose_from_imu);
    ba.AddWindowLandmarks(*map, local, &pose_index, options_.max_fixed_keyframes,
                          options_.point_sigma_px, options_.line_sigma_px);
    if (inertial) ba.AddInertialFactors(*map, local, &pose_index);
  }
  window->ms +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return true;
}

void LocalMapper::Solve(Window* window) {
  const auto start = std::chrono::steady_clock::now();
  // The solve runs without the map lock: tracking goes on meanwhile. An interruption asked for
  // before this point (while the keyframe waited in the queue) is dropped: this BA is the newer
  // window already. (A request that lands between this store and the solve's first check stops
  // it early: harmless, the next keyframe is on its way.) Overlapped solves are never
  // interrupted (their result must not depend on timing).
  interrupt_ba_.store(false);
  window->report = SolveBundleAdjustment(rig_, &window->ba.problem(), options_.ba, nullptr,
                                         overlap_ ? nullptr : &interrupt_ba_);
  window->solve_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  window->ms += window->solve_ms;
}

void LocalMapper::Finish(Window* window) {
  const auto start = std::chrono::steady_clock::now();
  Map* map = window->map;
  const int keyframe_id = window->keyframe_id;
  const MapBundleAdjustment& ba = window->ba;
  const BundleAdjustmentReport& report = window->report;
  const TriangulationStats& triangulated = window->triangulated;
  MutexLock lock(map->mutex());
  // A global BA that finished meanwhile (threaded mode), or a loop correction or merge while the
  // solve was pending (overlap), moved the map: this window's solution is in the old world and
  // is dropped (the next keyframe's window starts from the new one).
  if (report.solved && map->correction_epoch() == ba.correction_epoch()) ba.Apply(map, report);

  // Landmark culling: unobserved points and lines, and those tracking rarely finds where it
  // expects them.
  int points_culled = 0, lines_culled = 0;
  std::vector<int> erase_points, erase_lines;
  for (const auto& [pid, p] : map->points()) {
    const bool unreliable = p->visible >= 4 && p->found < options_.min_found_ratio * p->visible;
    const bool stale = p->observations.empty() ||
                       (keyframe_id - p->first_keyframe >= 3 && p->observations.size() < 2);
    if (unreliable || stale) erase_points.push_back(pid);
  }
  for (const auto& [lid, l] : map->lines()) {
    const bool unreliable = l->visible >= 4 && l->found < options_.min_found_ratio * l->visible;
    const bool stale = l->observations.empty() ||
                       (keyframe_id - l->first_keyframe >= 3 && l->observations.size() < 2);
    if (unreliable || stale) erase_lines.push_back(lid);
  }
  for (int pid : erase_points) map->ErasePoint(pid);
  for (int lid : erase_lines) map->EraseLine(lid);
  points_culled = static_cast<int>(erase_points.size());
  lines_culled = static_cast<int>(erase_lines.size());
  map->UpdateConnections(keyframe_id);

  // Keyframe culling among the covisible keyframes (never the first or the newest). The map is
  // empty when a merge moved its content into another while an overlapped solve was pending.
  int keyframes_culled = 0;
  if (options_.cull_keyframes && !map->keyframes().empty()) {
    const int first_keyframe = map->keyframes().begin()->first;
    for (int kf_id : map->BestCovisible(keyframe_id, options_.local_keyframes)) {
      // Never the first keyframe, this one, or newer ones still queued (threaded mode).
      if (kf_id == first_keyframe || kf_id >= keyframe_id) continue;
      auto kf = map->keyframe(kf_id);
      if (!kf) continue;
      int total = 0, redundant = 0;
      for (int pid : kf->point_ids) {
        auto p = pid >= 0 ? map->point(pid) : nullptr;
        if (!p) continue;
        ++total;
        if (static_cast<int>(p->observations.size()) - 1 >= options_.redundant_observers) {
          ++redundant;
        }
      }
      if (total > 0 && redundant > options_.redundant_ratio * total &&
          !LongImuInterval(*map, *kf)) {
        map->EraseKeyFrame(kf_id);
        ++keyframes_culled;
      }
    }
    // Points that culling left without observations go too.
    std::vector<int> orphans;
    for (const auto& [pid, p] : map->points()) {
      if (p->observations.empty()) orphans.push_back(pid);
    }
    for (int pid : orphans) map->ErasePoint(pid);
    points_culled += static_cast<int>(orphans.size());
  }

  const double ms =
      window->ms +
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::lock_guard<std::mutex> stats_lock(queue_mutex_);
  stats_.keyframes_processed += 1;
  stats_.keyframes_culled += keyframes_culled;
  stats_.points_culled += points_culled;
  stats_.lines_culled += lines_culled;
  stats_.points_triangulated += triangulated.points;
  stats_.lines_triangulated += triangulated.lines;
  stats_.total_ba_ms += ms;
  stats_.ba_interrupted += report.interrupted ? 1 : 0;
  stats_.ba_solve_ms += window->solve_ms;
  stats_.ba_iterations += report.iterations;
  stats_.ba_rejected_steps += report.rejected_steps;
  stats_.ba_inertial_factors += static_cast<int>(ba.problem().inertial.factors.size());
}

}  // namespace slslam
