#include "slslam/pipeline/tracker_session.h"

#include <chrono>

#include "slslam/core/check.h"

namespace slslam {

namespace {

// The tracker's options with the line front end's descriptor kind (for map files).
TrackerOptions WithLineDescriptor(TrackerOptions options, LineDescriptor descriptor) {
  options.line_descriptor = descriptor;
  return options;
}

}  // namespace

TrackerSession::TrackerSession(const TrackerOptions& options, const LineExtractorOptions& lines)
    : tracker_(WithLineDescriptor(options, lines.descriptor)),
      frontend_({options.rig, options.stereo, lines, options.use_lines,
                 options.right_lines_on_keyframes,
                 options.use_lines && options.right_lines_on_keyframes && options.lines_on_demand,
                 options.denoise_above_noise}) {}

FrameOutput TrackerSession::Track(int index, int64_t t_ns, const cv::Mat& left,
                                  const cv::Mat& right, const Keypoints& left_keypoints,
                                  const Keypoints& right_keypoints,
                                  const std::shared_ptr<LeftLines>& left_lines, bool noisy,
                                  bool denoised) {
  return TrackPrepared(*Prepare(index, t_ns, left, right, left_keypoints, right_keypoints,
                                left_lines, /*keypoints_pending=*/false, noisy, denoised));
}

std::shared_ptr<PreparedFrame> TrackerSession::Prepare(int index, int64_t t_ns, const cv::Mat& left,
                                                       const cv::Mat& right,
                                                       const Keypoints& left_keypoints,
                                                       const Keypoints& right_keypoints,
                                                       const std::shared_ptr<LeftLines>& left_lines,
                                                       bool keypoints_pending, bool noisy,
                                                       bool denoised) const {
  auto p = std::make_shared<PreparedFrame>();
  p->session = this;
  p->left_lines = left_lines;
  p->denoised = denoised;
  p->left = left.clone();
  p->right = right.clone();
  // lines_on_demand: lines extracted ahead are the completer's to hand over if the tracker asks
  // (the same lines it would extract: only the time differs).
  const LineFeatures* ahead = left_lines ? &left_lines->features : nullptr;
  p->frame = frontend_.Build(index, t_ns, p->left, p->right, left_keypoints, right_keypoints,
                             &p->timing, frontend_.options().left_lines_on_demand ? nullptr : ahead,
                             &p->left_used, &p->right_used, denoised);
  if (keypoints_pending) {
    SLSLAM_CHECK(left_keypoints.size() == 0 && right_keypoints.size() == 0,
                 "a frame prepared with keypoints_pending has no keypoints (",
                 left_keypoints.size(), " / ", right_keypoints.size(), " given)");
    p->frame->keypoints_pending = true;
  }
  p->frame->noisy = noisy;
  return p;
}

FrameOutput TrackerSession::TrackPrepared(PreparedFrame& p) {
  SLSLAM_CHECK(p.session == this,
               "a prepared frame is tracked by the TrackerCore that prepared it (its rig and "
               "options)");
  FrameOutput out;
  static_cast<StereoFrontendTiming&>(out) = p.timing;
  const LineFeatures* ahead = p.left_lines ? &p.left_lines->features : nullptr;
  if (p.left_lines) out.line_extraction_ms = p.left_lines->extraction_ms;
  MutexLock lock(mutex_);  // one call at a time from any thread
  SLSLAM_CHECK(!p.used, "a prepared frame is tracked once");
  p.used = true;
  // (right_lines_on_keyframes: the right image's lines when the tracker needs them)
  const Tracker::StereoLineCompleter complete = [&](StereoFrame* f) {
    frontend_.CompleteStereoLines(p.right, f, p.denoised);
  };
  // (lines_on_demand: the left image's lines when the tracker needs them)
  const Tracker::StereoLineCompleter complete_left = [&](StereoFrame* f) {
    frontend_.CompleteLeftLines(p.left, f, ahead, p.denoised);
  };
  static_cast<TrackResult&>(out) =
      tracker_.Track(p.frame, complete, p.left_used, complete_left, p.right_used);
  out.lines = out.frame_lines;
  if (!ahead) out.line_extraction_ms += out.left_lines_ms;
  return out;
}

std::shared_ptr<LeftLines> TrackerSession::ExtractLeftLines(const cv::Mat& left,
                                                            bool denoised) const {
  auto out = std::make_shared<LeftLines>();
  const auto start = std::chrono::steady_clock::now();
  out->features = frontend_.ExtractLeftLines(left, denoised);
  out->extraction_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return out;
}

void TrackerSession::AddImu(const Eigen::Matrix<int64_t, Eigen::Dynamic, 1>& t_ns,
                            const Eigen::Matrix<double, Eigen::Dynamic, 3>& gyro,
                            const Eigen::Matrix<double, Eigen::Dynamic, 3>& acc) {
  SLSLAM_CHECK(gyro.rows() == t_ns.size() && acc.rows() == t_ns.size(),
               "IMU samples: ", t_ns.size(), " times, ", gyro.rows(), " gyro rows, ", acc.rows(),
               " accelerometer rows");
  MutexLock lock(mutex_);
  for (Eigen::Index i = 0; i < t_ns.size(); ++i) {
    tracker_.AddImu(t_ns[i], gyro.row(i).transpose(), acc.row(i).transpose());
  }
}

SessionMap TrackerSession::Map(bool settle) {
  MutexLock lock(mutex_);
  if (settle) tracker_.Flush();
  SessionMap out;
  out.map = tracker_.ExportMap();
  out.mapping = tracker_.mapping_stats();
  out.maps = tracker_.live_maps();
  out.tracking = tracker_.stats();
  out.imu = tracker_.inertial_report();
  out.loops = tracker_.loop_stats();
  out.loop_events = tracker_.loop_events();
  return out;
}

void TrackerSession::SaveMap(const std::string& path, const std::string& version) {
  MutexLock lock(mutex_);
  tracker_.SaveMap(path, version);
}

void TrackerSession::LoadMap(const std::string& path) {
  MutexLock lock(mutex_);
  tracker_.LoadMap(path);
}

std::vector<FramePose> TrackerSession::Trajectory() {
  MutexLock lock(mutex_);
  tracker_.Flush();
  return tracker_.Trajectory();
}

void TrackerSession::Flush() {
  MutexLock lock(mutex_);
  tracker_.Flush();
}

}  // namespace slslam
