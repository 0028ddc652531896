// Tracker: the local map around the reference keyframe, copied under the map lock
// (SnapshotLocalMap) and matched in the frame with the motion-only BA outside it (TrackSnapshot);
// matched keypoints aligned to their map points' patches (RefineTracks); the
// dynamic-cell filter's update from the previous frame.
#include "slslam/tracking/tracker.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <opencv2/core/utility.hpp>

#include "slslam/features/line_segment.h"
#include "slslam/tracking/tracker_internal.h"

namespace slslam {

using tracker_detail::Clock;
using tracker_detail::InImage;
using tracker_detail::Ms;
using tracker_detail::SameKind;

Tracker::LocalMapSnapshot Tracker::SnapshotLocalMap(const StereoFrame& frame, Map& map,
                                                    int reference_kf,
                                                    const Rigid3d& pred_cam_from_world,
                                                    bool points_visible) const {
  const PinholeCamera& camera = options_.rig.camera;
  const auto start = Clock::now();
  LocalMapSnapshot snap;
  // Local map: the reference keyframe and its covisible keyframes.
  std::vector<int> local = {reference_kf};
  if (!map.keyframe(reference_kf)) local.clear();
  for (int id : map.BestCovisible(reference_kf, options_.mapping.local_keyframes)) {
    local.push_back(id);
  }
  if (local.empty() && !map.keyframes().empty()) local.push_back(map.keyframes().rbegin()->first);
  // The local keyframes' point and line ids, ascending and each once (sorted vectors: a std::set
  // of them was a fifth of this function's time).
  std::vector<int> point_ids, line_ids;
  for (int id : local) {
    auto kf = map.keyframe(id);
    if (!kf) continue;
    for (int pid : kf->point_ids) {
      if (pid >= 0) point_ids.push_back(pid);
    }
    for (int lid : kf->line_ids) {
      if (lid >= 0) line_ids.push_back(lid);
    }
  }
  for (std::vector<int>* ids : {&point_ids, &line_ids}) {
    std::sort(ids->begin(), ids->end());
    ids->erase(std::unique(ids->begin(), ids->end()), ids->end());
  }

  // Points in front of the predicted camera and inside the image.
  std::vector<MapPoint*> points;
  std::vector<Eigen::Vector2f> predicted;
  // The descriptors' kind: the frame's (none for a frame without keypoints)
  const cv::Mat* kind = frame.NumKeypoints() > 0 ? &frame.keypoints.descriptors : nullptr;
  // (one walk along the map's ordered points for the ascending ids: a tree search per id was
  // 0.6 % of an XFeat + lines run, perf)
  for (MapPoint* p : map.PointsOf(point_ids)) {
    if (!p || p->bad) continue;
    const Eigen::Vector3d x_c = pred_cam_from_world * p->position;
    if (x_c.z() <= 0.05) continue;
    const Eigen::Vector2d uv = camera.Project(x_c);
    if (!InImage(camera, uv)) continue;
    // A descriptor of another kind (a loaded map of another front end) cannot be matched.
    if (kind != nullptr && !SameKind(p->descriptor, *kind)) continue;
    // (a frame without keypoints yet, projected_max_frames, takes the first point's kind)
    if (kind == nullptr && frame.keypoints_pending) kind = &p->descriptor;
    points.push_back(p);
    predicted.push_back(uv.cast<float>());
    if (points_visible) p->visible += 1;
  }
  if (!points.empty() && kind != nullptr) {
    const cv::Mat& frame_desc = *kind;
    snap.point_uv.resize(static_cast<Eigen::Index>(points.size()), 2);
    snap.point_descriptors =
        cv::Mat(static_cast<int>(points.size()), frame_desc.cols, frame_desc.type());
    // (each descriptor one continuous row of the frame's kind, SameKind: copied as bytes, without
    // the two row headers and the dispatch of cv::Mat::copyTo)
    const size_t row_bytes = frame_desc.elemSize() * static_cast<size_t>(frame_desc.cols);
    snap.point_ids.reserve(points.size());
    snap.point_w.reserve(points.size());
    snap.point_patches.reserve(points.size());
    snap.point_patch_depth_m.reserve(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      snap.point_ids.push_back(points[i]->id);
      snap.point_w.push_back(points[i]->position);
      snap.point_uv.row(static_cast<Eigen::Index>(i)) = predicted[i].transpose();
      std::memcpy(snap.point_descriptors.ptr(static_cast<int>(i)), points[i]->descriptor.ptr(0),
                  row_bytes);
      snap.point_patches.push_back(points[i]->patch);  // (shared pixels: never written again)
      snap.point_patch_depth_m.push_back(points[i]->patch_depth_m);
    }
  }

  // Lines whose predicted segment is in front of the camera, long enough and centred inside.
  if (options_.use_lines && frame.NumLines() > 0) {
    std::vector<std::shared_ptr<MapLine>> lines;
    for (int lid : line_ids) {
      auto l = map.line(lid);
      if (!l || l->bad) continue;
      LineSegment proj;
      if (!ProjectMapLine(*l, pred_cam_from_world, &proj)) continue;
      if (!SameKind(l->descriptor, frame.line_descriptors)) continue;
      l->visible += 1;
      lines.push_back(l);
      snap.line_px.push_back(proj);
    }
    if (!lines.empty()) {
      const cv::Mat& kind = frame.line_descriptors;
      snap.line_descriptors = cv::Mat(static_cast<int>(lines.size()), kind.cols, kind.type());
      for (size_t i = 0; i < lines.size(); ++i) {
        snap.line_ids.push_back(lines[i]->id);
        snap.lines_w.push_back(lines[i]->line);
        lines[i]->descriptor.copyTo(snap.line_descriptors.row(static_cast<int>(i)));
      }
    }
  }
  snap.ms = Ms(start);
  return snap;
}

bool Tracker::ProjectMapLine(const MapLine& line, const Rigid3d& cam_from_world,
                             LineSegment* proj) const {
  const PinholeCamera& camera = options_.rig.camera;
  if (LineAided()) {
    // The part in front and inside the image: a long edge the camera drives along reaches
    // behind it, and its near end leaves the image first.
    Eigen::Vector3d s_c, e_c;
    if (!tracker_detail::ClipToFront(cam_from_world, line.start, line.end,
                                     tracker_detail::kMinLineDepthM, &s_c, &e_c)) {
      return false;
    }
    proj->start = camera.Project(s_c).cast<float>();
    proj->end = camera.Project(e_c).cast<float>();
    return tracker_detail::ClipToImage(camera, proj) && proj->Length() >= 5.0f;
  }
  const Eigen::Vector3d s_c = cam_from_world * line.start;
  const Eigen::Vector3d e_c = cam_from_world * line.end;
  if (s_c.z() <= 0.05 || e_c.z() <= 0.05) return false;
  proj->start = camera.Project(s_c).cast<float>();
  proj->end = camera.Project(e_c).cast<float>();
  const Eigen::Vector2f mid = 0.5f * (proj->start + proj->end);
  return InImage(camera, mid.cast<double>()) && proj->Length() >= 5.0f;
}

Tracker::LocalTracking Tracker::TrackSnapshot(
    const StereoFrame& frame, const LocalMapSnapshot& local, const Rigid3d& pred_cam_from_world,
    float radius_scale, const std::vector<bool>* valid_keypoints, const cv::Mat* refine_image,
    const PosePrior* prior) const {
  LocalTracking out;
  const auto match_start = Clock::now();
  // Points: matched in a window around the predicted position.
  const cv::Mat& frame_desc = frame.keypoints.descriptors;
  if (!local.point_ids.empty() && frame.NumKeypoints() > 0) {
    GuidedMatchOptions guided = GuidedOptions(frame_desc.type(), radius_scale);
    Eigen::VectorXi m = GuidedMatch(local.point_uv, local.point_descriptors, frame.keypoints.uv,
                                    frame_desc, guided);
    if ((m.array() >= 0).count() < 30) {  // fast motion: widen the window once
      guided.radius_px *= 2.0f;
      m = GuidedMatch(local.point_uv, local.point_descriptors, frame.keypoints.uv, frame_desc,
                      guided);
    }
    for (size_t i = 0; i < local.point_ids.size(); ++i) {
      if (m(i) < 0) continue;
      const bool masked = valid_keypoints && !valid_keypoints->empty() && !(*valid_keypoints)[m(i)];
      (masked ? out.masked_point_ids : out.point_ids).push_back(static_cast<int>(i));
      (masked ? out.masked_keypoints : out.keypoints).push_back(m(i));
    }
  }
  RefineTracks(frame, local, pred_cam_from_world, refine_image, &out);

  // Lines: predicted segments against frame segments (angle, distance, LBD).
  std::vector<int> line_rows;  // snapshot rows of the matched lines
  if (options_.use_lines && frame.NumLines() > 0) {
    const float line_search = options_.line_search_px * radius_scale;
    std::vector<std::tuple<float, int, int>> pairs;  // (LBD distance, snapshot row, segment)
    for (size_t r = 0; r < local.line_ids.size(); ++r) {
      const LineSegment& proj = local.line_px[r];
      const Eigen::Vector2f mid = 0.5f * (proj.start + proj.end);
      for (int j = 0; j < frame.NumLines(); ++j) {
        const LineSegment& seg = frame.lines[j];
        if (AngleDifference(seg.Angle(), proj.Angle()) > options_.line_max_angle_rad) continue;
        const Eigen::Vector2f seg_mid = 0.5f * (seg.start + seg.end);
        if (proj.DistanceToLine(seg_mid) > line_search) continue;
        if ((seg_mid - mid).norm() > 0.5f * (proj.Length() + seg.Length()) + line_search) {
          continue;
        }
        const int row = static_cast<int>(r);
        const float d = DescriptorDistance(local.line_descriptors, row, frame.line_descriptors, j);
        if (d <= options_.line_max_lbd) pairs.emplace_back(d, row, j);
      }
    }
    // Rows are in id order, so (distance, row, segment) sorts as (distance, id, segment).
    std::sort(pairs.begin(), pairs.end());
    std::set<int> used_rows, used_segments;
    for (const auto& [d, r, j] : pairs) {
      (void)d;
      if (used_rows.count(r) || used_segments.count(j)) continue;
      used_rows.insert(r);
      used_segments.insert(j);
      line_rows.push_back(r);
      out.segments.push_back(j);
    }
  }
  out.matching_ms = local.ms + Ms(match_start);

  // Motion-only BA.
  const auto opt_start = Clock::now();
  std::vector<PointObservation> points(out.point_ids.size());
  // A noisy frame with enough aligned matches: the unaligned ones weigh less
  // (unaligned_sigma_factor). Tracking's own frames only (refine_image given): velocity_ is
  // the tracking thread's, and loop verification runs this on the mapping thread.
  double unaligned_sigma_px = options_.point_sigma_px;
  if (refine_image != nullptr && frame.noisy && options_.unaligned_sigma_factor > 1.0) {
    // (the turn of the motion model's last step: the frame before from the one before)
    const double turn_deg =
        Eigen::AngleAxisd(velocity_.rotation).angle() * 180.0 / 3.14159265358979323846;
    int aligned = 0;
    for (const Eigen::Vector2f& uv : out.refined_uv) aligned += std::isfinite(uv.x()) ? 1 : 0;
    if (turn_deg <= options_.unaligned_max_turn_deg_per_frame &&
        aligned >= options_.unaligned_min_aligned) {
      unaligned_sigma_px *= options_.unaligned_sigma_factor;
    }
  }
  for (size_t i = 0; i < out.point_ids.size(); ++i) {
    const int k = out.keypoints[i];
    points[i].point_w = local.point_w[out.point_ids[i]];
    points[i].stereo = frame.u_right[k] >= 0.0;
    points[i].observed = tracker_detail::ObservedPixel(frame, k, out.refined_uv[i]);
    points[i].sigma_px =
        std::isfinite(out.refined_uv[i].x()) ? options_.point_sigma_px : unaligned_sigma_px;
  }
  std::vector<LineObservation> lines(line_rows.size());
  for (size_t i = 0; i < line_rows.size(); ++i) {
    lines[i].line_w = local.lines_w[line_rows[i]];
    lines[i].start_px = frame.lines[out.segments[i]].start.cast<double>();
    lines[i].end_px = frame.lines[out.segments[i]].end.cast<double>();
    lines[i].sigma_px = options_.line_sigma_px;
  }
  out.pose = OptimizePose(options_.rig, pred_cam_from_world, points, lines, options_.pose, prior);
  out.weighted_inliers =
      out.pose.success ? Weighted(out.pose.point_inliers, out.pose.line_inliers) : 0.0;
  const int weak_lines = options_.imu.weak_update_min_lines;
  if (prior != nullptr && weak_lines > 0 && static_cast<int>(lines.size()) >= weak_lines &&
      out.weighted_inliers < options_.min_inliers) {
    // (the points' few matches on a smooth lining are noise: the lines alone with the prior)
    out.line_pose =
        OptimizePose(options_.rig, pred_cam_from_world, {}, lines, options_.pose, prior);
    // The lines' pose leaves a direction to the IMU: the one parallel lines share, else the
    // viewing direction, along which stereo lines are least determined.
    out.line_pose_along_world = tracker_detail::SharedDirection(lines, out.line_pose.line_inlier);
    if (out.line_pose_along_world.isZero(0.0)) {
      out.line_pose_along_world =
          pred_cam_from_world.rotation.transpose() * Eigen::Vector3d::UnitZ();
    }
  }
  out.optimisation_ms = Ms(opt_start);
  // Snapshot rows to map ids.
  for (int& row : out.point_ids) row = local.point_ids[row];
  for (int& row : out.masked_point_ids) row = local.point_ids[row];
  for (int row : line_rows) out.line_ids.push_back(local.line_ids[row]);
  return out;
}

Tracker::LocalTracking Tracker::TrackLocalMap(const StereoFrame& frame, Map& map, int reference_kf,
                                              const Rigid3d& pred_cam_from_world,
                                              float radius_scale,
                                              const std::vector<bool>* valid_keypoints) const {
  return TrackSnapshot(frame, SnapshotLocalMap(frame, map, reference_kf, pred_cam_from_world),
                       pred_cam_from_world, radius_scale, valid_keypoints);
}

GuidedMatchOptions Tracker::GuidedOptions(int descriptor_type, float radius_scale) const {
  GuidedMatchOptions guided;
  guided.radius_px = options_.search_radius_px * radius_scale;
  guided.max_distance =
      descriptor_type == CV_8U ? options_.max_distance_binary : options_.max_distance_float;
  guided.ratio = options_.match_ratio;
  return guided;
}

namespace tracker_detail {

void ExtendToSegment(const PinholeCamera& camera, const Rigid3d& cam_from_world,
                     const LineSegment& seg, double max_depth_m, MapLine* line) {
  const Eigen::Vector3d along = line->end - line->start;
  const double length = along.norm();
  if (length < 1e-9) return;
  const Eigen::Vector3d direction = along / length;
  const PluckerLine line_c = line->line.Transformed(cam_from_world);
  const Rigid3d world_from_cam = cam_from_world.Inverse();
  double t_min = 0.0, t_max = length;
  for (const Eigen::Vector2f& px : {seg.start, seg.end}) {
    const Eigen::Vector3d x_c = line_c.ClosestPointToRay(camera.Unproject(px.cast<double>()));
    // (a ray near the line's vanishing point meets it far away, or behind the camera)
    if (!x_c.allFinite() || x_c.z() <= 0.05 || x_c.z() > max_depth_m) continue;
    const double t = direction.dot(world_from_cam * x_c - line->start);
    t_min = std::min(t_min, t);
    t_max = std::max(t_max, t);
  }
  const Eigen::Vector3d start = line->start;
  line->start = start + t_min * direction;
  line->end = start + t_max * direction;
}

void AddStereoSupport(const Rigid3d& world_from_cam,
                      const std::array<Eigen::Vector3d, 2>& endpoints_cam, MapLine* line) {
  for (const Eigen::Vector3d& x_c : endpoints_cam) {
    if (!x_c.allFinite() || x_c.z() <= 0.0) continue;
    const double depth = std::max(x_c.z(), 0.5);  // (nearer: stereo is as good as it gets)
    line->stereo_support.emplace_back(world_from_cam * x_c, 1.0 / (depth * depth));
  }
}

void RefitToSupport(MapLine* line) {
  double w_sum = 0.0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& [p, w] : line->stereo_support) {
    centroid += w * p;
    w_sum += w;
  }
  if (line->stereo_support.size() < 3 || w_sum <= 0.0) return;
  centroid /= w_sum;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& [p, w] : line->stereo_support) {
    scatter += w * (p - centroid) * (p - centroid).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  if (eigen.info() != Eigen::Success) return;
  const Eigen::Vector3d direction = eigen.eigenvectors().col(2);  // (ascending eigenvalues)
  line->line = PluckerLine::FromPoints(centroid, centroid + direction);
  line->start = line->line.ClosestPointTo(line->start);
  line->end = line->line.ClosestPointTo(line->end);
}

Eigen::Vector3d SharedDirection(const std::vector<LineObservation>& lines,
                                const std::vector<bool>& inlier) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> directions;
  for (size_t i = 0; i < lines.size() && i < inlier.size(); ++i) {
    if (!inlier[i]) continue;
    Eigen::Vector3d v = lines[i].line_w.v.normalized();
    if (!directions.empty() && v.dot(directions.front()) < 0.0) v = -v;
    directions.push_back(v);
    sum += v;
  }
  if (directions.empty() || sum.norm() < 1e-9) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d mean = sum.normalized();
  const double min_cos = std::cos(kParallelLinesMaxRad);
  for (const Eigen::Vector3d& v : directions) {
    if (v.dot(mean) < min_cos) return Eigen::Vector3d::Zero();
  }
  return mean;
}

bool ClipToImage(const PinholeCamera& camera, LineSegment* seg) {
  // Liang-Barsky: the segment start + t (end - start), t in [t0, t1], against the four borders.
  const Eigen::Vector2f d = seg->end - seg->start;
  float t0 = 0.0f, t1 = 1.0f;
  const float lo[2] = {0.0f, 0.0f};
  const float hi[2] = {static_cast<float>(camera.width - 1), static_cast<float>(camera.height - 1)};
  for (int axis = 0; axis < 2; ++axis) {
    const float p = seg->start[axis];
    for (const auto& [q, r] : {std::pair<float, float>{-d[axis], p - lo[axis]},
                               std::pair<float, float>{d[axis], hi[axis] - p}}) {
      if (q == 0.0f) {
        if (r < 0.0f) return false;  // parallel to this border and outside it
        continue;
      }
      const float t = r / q;
      if (q < 0.0f) {
        t0 = std::max(t0, t);
      } else {
        t1 = std::min(t1, t);
      }
    }
  }
  if (t0 > t1) return false;
  const Eigen::Vector2f start = seg->start;
  seg->start = start + t0 * d;
  seg->end = start + t1 * d;
  return true;
}

bool ClipToFront(const Rigid3d& cam_from_world, const Eigen::Vector3d& start_w,
                 const Eigen::Vector3d& end_w, double min_depth_m, Eigen::Vector3d* start_c,
                 Eigen::Vector3d* end_c) {
  Eigen::Vector3d s = cam_from_world * start_w, e = cam_from_world * end_w;
  if (s.z() < min_depth_m && e.z() < min_depth_m) return false;
  if (s.z() < min_depth_m) s = e + (s - e) * ((e.z() - min_depth_m) / (e.z() - s.z()));
  if (e.z() < min_depth_m) e = s + (e - s) * ((s.z() - min_depth_m) / (s.z() - e.z()));
  *start_c = s;
  *end_c = e;
  return true;
}

bool AlignPatch(const cv::Mat& image, const cv::Mat& patch, double scale, double min_ncc, double* u,
                double* v) {
  // Inverse compositional (Baker and Matthews): the template's gradients and normal matrix are
  // computed once, each step samples the image once per patch pixel.
  const int size = patch.rows, w = size / 2, n = size * size;
  static thread_local std::vector<float> tm, tgx, tgy, values;  // (no allocation per call)
  tm.resize(n);
  tgx.resize(n);
  tgy.resize(n);
  values.resize(n);
  double t_mean = 0.0;
  for (int r = 0, k = 0; r < size; ++r) {
    const float* row = patch.ptr<float>(r);
    for (int c = 0; c < size; ++c, ++k) t_mean += row[c];
  }
  t_mean /= n;
  Eigen::Matrix2d h = Eigen::Matrix2d::Zero();
  double t_ss = 0.0;
  for (int r = 0, k = 0; r < size; ++r) {
    const float* row = patch.ptr<float>(r);
    const float* up = patch.ptr<float>(std::max(r - 1, 0));
    const float* down = patch.ptr<float>(std::min(r + 1, size - 1));
    const float dy = (r == 0 || r == size - 1) ? 1.0f : 0.5f;
    for (int c = 0; c < size; ++c, ++k) {
      const int left = std::max(c - 1, 0), right = std::min(c + 1, size - 1);
      tm[k] = static_cast<float>(row[c] - t_mean);
      tgx[k] = (row[right] - row[left]) * ((c == 0 || c == size - 1) ? 1.0f : 0.5f);
      tgy[k] = (down[c] - up[c]) * dy;
      h(0, 0) += tgx[k] * tgx[k];
      h(0, 1) += tgx[k] * tgy[k];
      h(1, 1) += tgy[k] * tgy[k];
      t_ss += static_cast<double>(tm[k]) * tm[k];
    }
  }
  h(1, 0) = h(0, 1);
  // Texture: the smaller eigenvalue of the normal matrix, per pixel, in gray levels^2 (flat or
  // edge-only patches cannot be aligned in both directions).
  const double trace = h(0, 0) + h(1, 1);
  const double det = h(0, 0) * h(1, 1) - h(0, 1) * h(0, 1);
  const double min_eigen = 0.5 * (trace - std::sqrt(std::max(0.0, trace * trace - 4.0 * det)));
  if (min_eigen < 1.0 * n) return false;
  const Eigen::Matrix2d h_inv = h.inverse();
  double x = *u, y = *v;
  const double reach = w * scale + 1.0;
  for (int iteration = 0; iteration < 10; ++iteration) {
    if (x - reach < 0.0 || y - reach < 0.0 || x + reach > image.cols - 1.0 ||
        y + reach > image.rows - 1.0) {
      return false;
    }
    double mean = SampleGrid(image, x, y, w, scale, values.data());
    mean /= n;
    Eigen::Vector2d b = Eigen::Vector2d::Zero();
    double i_ss = 0.0, i_t = 0.0;
    for (int k = 0; k < n; ++k) {
      const double i = values[k] - mean;
      const double e = i - tm[k];
      b(0) += tgx[k] * e;
      b(1) += tgy[k] * e;
      i_ss += i * i;
      i_t += i * tm[k];
    }
    // The image shows the template moved by delta: the patch centre moves back by it.
    const Eigen::Vector2d delta = h_inv * b;
    x -= scale * delta.x();
    y -= scale * delta.y();
    if (scale * scale * delta.squaredNorm() < 1e-4) {
      if (i_t < min_ncc * std::sqrt(std::max(1e-12, i_ss * t_ss))) return false;
      *u = x;
      *v = y;
      return true;
    }
  }
  return false;
}

}  // namespace tracker_detail

void Tracker::RefineTracks(const StereoFrame& frame, const LocalMapSnapshot& local,
                           const Rigid3d& pred_cam_from_world, const cv::Mat* image,
                           LocalTracking* tracking) const {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  tracking->refined_uv.assign(tracking->keypoints.size(), Eigen::Vector2f::Constant(kNaN));
  if (options_.track_refine_window_px <= 0 || image == nullptr || image->empty()) return;
  const float max_sq = options_.track_refine_max_px * options_.track_refine_max_px;
  // The matches in parallel stripes on OpenCV's threads: each writes its own refined_uv entry
  // (AlignPatch's buffers are per thread). On one thread the alignment is a large share of a
  // tracked frame's time in the core (ORB points; benchmarks/log/realtime.md).
  const int n = static_cast<int>(tracking->keypoints.size());
  cv::parallel_for_(
      cv::Range(0, n),
      [&](const cv::Range& range) {
        for (int i = range.start; i < range.end; ++i) {
          const int row = tracking->point_ids[i];
          const cv::Mat& patch = local.point_patches[row];
          if (patch.empty()) continue;
          // The patch grows as the point comes closer: image pixels per patch pixel.
          const double depth = (pred_cam_from_world * local.point_w[row]).z();
          if (depth <= 0.05) continue;
          const double scale = local.point_patch_depth_m[row] / depth;
          if (scale < 0.5 || scale > 2.0) continue;
          const int k = tracking->keypoints[i];
          double u = frame.keypoints.uv(k, 0), v = frame.keypoints.uv(k, 1);
          constexpr double kMinNcc = 0.8;  // (a patch that no longer looks like the point)
          if (!tracker_detail::AlignPatch(*image, patch, scale, kMinNcc, &u, &v)) continue;
          const Eigen::Vector2f refined(static_cast<float>(u), static_cast<float>(v));
          if ((refined - frame.keypoints.uv.row(k).transpose()).squaredNorm() > max_sq) continue;
          tracking->refined_uv[i] = refined;
        }
      },
      4);
}

std::shared_ptr<const StereoFrame> Tracker::WithRefinedKeypoints(
    std::shared_ptr<const StereoFrame> frame, const LocalTracking& tracking) const {
  if (tracking.refined_uv.size() != tracking.point_ids.size()) return frame;
  std::shared_ptr<StereoFrame> copy;
  for (size_t i = 0; i < tracking.point_ids.size() && i < tracking.pose.point_inlier.size(); ++i) {
    const Eigen::Vector2f& refined = tracking.refined_uv[i];
    if (!tracking.pose.point_inlier[i] || !std::isfinite(refined.x())) continue;
    if (!copy) copy = std::make_shared<StereoFrame>(*frame);
    const int k = tracking.keypoints[i];
    const Eigen::Vector3d observed = tracker_detail::ObservedPixel(*frame, k, refined);
    copy->keypoints.uv.row(k) = refined.transpose();
    copy->u_right[k] = observed.z();
  }
  if (!copy) return frame;
  return copy;
}

void Tracker::UpdateDynamicCells(const StereoFrame& frame, const Rigid3d& cam_from_world) {
  // Frame-to-frame evidence, as the paper's filter: the previous frame's stereo keypoints are
  // carried into this frame by the camera motion between the two estimated poses and matched
  // around their predicted pixels; a cell whose matches land far from the prediction moved on
  // its own. Unlike matches to the map, these exist for a mover too (it makes no map points once
  // its cells are invalid), so its cells stay invalid while it moves.
  // The caller replaces previous_frame_ with this frame afterwards.
  const StereoFrame* previous = previous_frame_.get();
  if (!previous || previous->NumKeypoints() == 0 || frame.NumKeypoints() == 0 ||
      previous->keypoints.descriptors.type() != frame.keypoints.descriptors.type()) {
    return;
  }
  const PinholeCamera& camera = options_.rig.camera;
  // x_cur = R_cp x_prev + t_cp: R_cp = R_cw R_pw^T, t_cp = t_cw - R_cp t_pw.
  Rigid3d cam_from_prev;
  cam_from_prev.rotation = cam_from_world.rotation * previous_cam_from_world_.rotation.transpose();
  cam_from_prev.translation =
      cam_from_world.translation - cam_from_prev.rotation * previous_cam_from_world_.translation;
  std::vector<int> rows;
  PixelArray predicted(previous->NumKeypoints(), 2);
  for (int i = 0; i < previous->NumKeypoints(); ++i) {
    if (!(previous->depth[i] > 0.0)) continue;
    const Eigen::Vector3d x_c = cam_from_prev * previous->Backproject(camera, i);
    if (x_c.z() <= 0.05) continue;
    const Eigen::Vector2d uv = camera.Project(x_c);
    if (!InImage(camera, uv)) continue;
    predicted.row(static_cast<Eigen::Index>(rows.size())) = uv.cast<float>().transpose();
    rows.push_back(i);
  }
  const cv::Mat& desc = frame.keypoints.descriptors;
  cv::Mat query(static_cast<int>(rows.size()), desc.cols, desc.type());
  for (size_t r = 0; r < rows.size(); ++r) {
    previous->keypoints.descriptors.row(rows[r]).copyTo(query.row(static_cast<int>(r)));
  }
  const GuidedMatchOptions guided = GuidedOptions(desc.type(), 1.0f);
  const PixelArray pred = predicted.topRows(static_cast<Eigen::Index>(rows.size()));
  const Eigen::VectorXi m = GuidedMatch(pred, query, frame.keypoints.uv, desc, guided);
  PixelArray observed(m.size(), 2), expected(m.size(), 2);
  Eigen::Index n = 0;
  for (Eigen::Index r = 0; r < m.size(); ++r) {
    if (m(r) < 0) continue;
    observed.row(n) = frame.keypoints.uv.row(m(r));
    expected.row(n) = pred.row(r);
    ++n;
  }
  dynamic_->Update(observed.topRows(n), expected.topRows(n));
}

}  // namespace slslam
