// The per-frame session over the tracker: the stereo front end (lines, stereo matching) that
// builds each frame from the images and the point features, the tracker with local mapping and
// loop closing, and the calls a frame pipeline makes on them (a frame prepared on one thread
// while the previous one is tracked on another, left lines extracted ahead, IMU samples, the
// map, the trajectory, map files). Python's slslam.Tracker drives one through slslam._core's
// TrackerCore, which only converts arrays and releases the GIL.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slslam/core/thread_annotations.h"
#include "slslam/features/keypoints.h"
#include "slslam/features/line_extractor.h"
#include "slslam/tracking/stereo_frontend.h"
#include "slslam/tracking/tracker.h"

namespace slslam {

// One frame through the session: the tracker's result, the front end's stage times and the
// number of left-image line segments.
struct FrameOutput : TrackResult, StereoFrontendTiming {
  int lines = 0;
};

// A left image's lines extracted ahead of its frame (TrackerSession::ExtractLeftLines).
struct LeftLines {
  LineFeatures features;
  double extraction_ms = 0.0;
};

// A frame whose stereo matching ran ahead of the tracker (TrackerSession::Prepare): the frame,
// the images it was built from (copies) and the lines extracted beside it.
struct PreparedFrame {
  const void* session = nullptr;  ///< the TrackerSession that prepared it (and tracks it)
  cv::Mat left, right, left_used, right_used;
  std::shared_ptr<StereoFrame> frame;
  std::shared_ptr<LeftLines> left_lines;
  StereoFrontendTiming timing;
  bool used = false;      ///< tracked (under the session's lock): a frame is tracked once
  bool denoised = false;  ///< the caller smoothed the images (StereoFrontend::Build's denoised)
};

// The map and the run's counters at one moment (TrackerSession::Map).
struct SessionMap {
  MapExport map;
  int maps = 0;
  LocalMappingStats mapping;
  TrackingStats tracking;
  Tracker::InertialReport imu;
  LoopClosingStats loops;
  std::vector<LoopEvent> loop_events;
};

class TrackerSession {
 public:
  TrackerSession(const TrackerOptions& options, const LineExtractorOptions& lines);

  // Prepare + TrackPrepared.
  FrameOutput Track(int index, int64_t t_ns, const cv::Mat& left, const cv::Mat& right,
                    const Keypoints& left_keypoints, const Keypoints& right_keypoints,
                    const std::shared_ptr<LeftLines>& left_lines, bool noisy, bool denoised);

  // Track's first part, the frame's stereo matching (StereoFrontend::Build), without the
  // session's lock: it reads no state of the tracker, so a pipeline's worker runs it for frame
  // k + 1 while the tracker works on frame k. The images are copied (the frame outlives them).
  std::shared_ptr<PreparedFrame> Prepare(int index, int64_t t_ns, const cv::Mat& left,
                                         const cv::Mat& right, const Keypoints& left_keypoints,
                                         const Keypoints& right_keypoints,
                                         const std::shared_ptr<LeftLines>& left_lines,
                                         bool keypoints_pending, bool noisy, bool denoised) const;

  // Track's second part: the tracker (and local mapping) on a prepared frame, one call at a
  // time and in frame order.
  FrameOutput TrackPrepared(PreparedFrame& p) SLSLAM_EXCLUDES(mutex_);

  // The left image's lines, as Track would extract them, on the calling thread without the
  // session's lock (beside the point front end, or beside Track of the previous frame).
  std::shared_ptr<LeftLines> ExtractLeftLines(const cv::Mat& left, bool denoised) const;

  // IMU samples (times [ns] on the IMU's clock, gyro [rad/s], specific force [m/s^2], one row
  // each), before the frames they precede.
  void AddImu(const Eigen::Matrix<int64_t, Eigen::Dynamic, 1>& t_ns,
              const Eigen::Matrix<double, Eigen::Dynamic, 3>& gyro,
              const Eigen::Matrix<double, Eigen::Dynamic, 3>& acc) SLSLAM_EXCLUDES(mutex_);

  // The map and the counters; `settle` waits for local mapping (and loop closing) first.
  SessionMap Map(bool settle) SLSLAM_EXCLUDES(mutex_);
  void SaveMap(const std::string& path, const std::string& version) SLSLAM_EXCLUDES(mutex_);
  void LoadMap(const std::string& path) SLSLAM_EXCLUDES(mutex_);
  // Every estimated frame pose in the final (loop-corrected, merged) map, after a Flush.
  std::vector<FramePose> Trajectory() SLSLAM_EXCLUDES(mutex_);
  void Flush() SLSLAM_EXCLUDES(mutex_);

 private:
  // First: its option checks (named by YAML key) run before the front end's.
  Tracker tracker_ SLSLAM_GUARDED_BY(mutex_);
  StereoFrontend frontend_;
  Mutex mutex_;
};

}  // namespace slslam
