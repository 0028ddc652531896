#include "slslam/features/line_matcher.h"

#include <algorithm>
#include <limits>
#include <map>

#include "slslam/core/check.h"

namespace slslam {

void LineMatchOptions::Check() const {
  CheckInRange("line_match.min_votes", min_votes, 1, limits::kMaxKeypoints);
  CheckAboveInRange("line_match.max_lbd_distance", max_lbd_distance, 0.0f, limits::kLbdBits);
  CheckAboveInRange("line_match.max_angle_rad", max_angle_rad, 0.0f, limits::kPi);
}

void StereoLineOptions::Check() const {
  CheckAboveInRange("stereo_lines.min_row_overlap", min_row_overlap, 0.0f, 1.0f);
  CheckAboveInRange("stereo_lines.max_lbd_distance", max_lbd_distance, 0.0f, limits::kLbdBits);
  CheckAboveInRange("stereo_lines.max_angle_rad", max_angle_rad, 0.0f, limits::kPi);
  CheckInRange("stereo_lines.min_angle_from_horizontal_rad", min_angle_from_horizontal_rad, 0.0f,
               limits::kPi / 2);
  CheckInRange("stereo_lines.min_disparity_px", min_disparity_px, 0.0f,
               limits::kMaxImageDistancePx);
}

namespace {

float LbdDistance(const cv::Mat& a, int i, const cv::Mat& b, int j) {
  return static_cast<float>(cv::norm(a.row(i), b.row(j), cv::NORM_HAMMING));
}

// Keeps, for every line of B, only its best (lowest cost) pair.
IndexPairs UniqueByCost(const std::vector<std::pair<float, std::pair<int, int>>>& candidates) {
  std::map<int, std::pair<float, int>> best_for_b;
  for (const auto& [cost, pair] : candidates) {
    auto it = best_for_b.find(pair.second);
    if (it == best_for_b.end() || cost < it->second.first) {
      best_for_b[pair.second] = {cost, pair.first};
    }
  }
  std::vector<std::pair<int, int>> kept;
  for (const auto& [b, entry] : best_for_b) kept.emplace_back(entry.second, b);
  std::sort(kept.begin(), kept.end());
  IndexPairs out(static_cast<Eigen::Index>(kept.size()), 2);
  for (size_t k = 0; k < kept.size(); ++k) out.row(k) << kept[k].first, kept[k].second;
  return out;
}

}  // namespace

IndexPairs MatchLinesByPoints(const Segments& lines_a,
                              const std::vector<std::vector<int>>& points_a, const cv::Mat& lbd_a,
                              const Segments& lines_b,
                              const std::vector<std::vector<int>>& points_b, const cv::Mat& lbd_b,
                              const IndexPairs& point_matches, const LineMatchOptions& options) {
  options.Check();
  Require(points_a.size() == lines_a.size() && points_b.size() == lines_b.size(),
          "one keypoint list per line is needed");
  Require(lbd_a.rows == static_cast<int>(lines_a.size()) &&
              lbd_b.rows == static_cast<int>(lines_b.size()),
          "one LBD descriptor per line is needed");
  // Keypoint of A -> its partner in B, and keypoint of B -> the lines of B holding it.
  std::map<int, int> partner;
  for (Eigen::Index k = 0; k < point_matches.rows(); ++k) {
    partner[point_matches(k, 0)] = point_matches(k, 1);
  }
  std::map<int, std::vector<int>> lines_of_b_point;
  for (size_t j = 0; j < points_b.size(); ++j) {
    for (int p : points_b[j]) lines_of_b_point[p].push_back(static_cast<int>(j));
  }
  std::vector<std::pair<float, std::pair<int, int>>> candidates;
  for (size_t i = 0; i < lines_a.size(); ++i) {
    std::map<int, int> votes;
    for (int p : points_a[i]) {
      const auto it = partner.find(p);
      if (it == partner.end()) continue;
      const auto lines = lines_of_b_point.find(it->second);
      if (lines == lines_of_b_point.end()) continue;
      for (int j : lines->second) ++votes[j];
    }
    int best_j = -1, best_votes = 0;
    float best_distance = std::numeric_limits<float>::infinity();
    for (const auto& [j, v] : votes) {
      if (v < options.min_votes) continue;
      if (AngleDifference(lines_a[i].Angle(), lines_b[j].Angle()) > options.max_angle_rad) continue;
      const float d = LbdDistance(lbd_a, static_cast<int>(i), lbd_b, j);
      if (d > options.max_lbd_distance) continue;
      if (v > best_votes || (v == best_votes && d < best_distance)) {
        best_j = j;
        best_votes = v;
        best_distance = d;
      }
    }
    // Cost for uniqueness: more votes first, then LBD distance.
    if (best_j >= 0) {
      candidates.push_back({-1000.0f * best_votes + best_distance, {static_cast<int>(i), best_j}});
    }
  }
  return UniqueByCost(candidates);
}

IndexPairs MatchStereoLines(const Segments& left, const cv::Mat& lbd_left, const Segments& right,
                            const cv::Mat& lbd_right, const StereoLineOptions& options) {
  options.Check();
  Require(lbd_left.rows == static_cast<int>(left.size()) &&
              lbd_right.rows == static_cast<int>(right.size()),
          "one LBD descriptor per line is needed");
  std::vector<std::pair<float, std::pair<int, int>>> candidates;
  for (size_t i = 0; i < left.size(); ++i) {
    const LineSegment& l = left[i];
    const float from_horizontal = std::min(l.Angle(), static_cast<float>(M_PI) - l.Angle());
    if (from_horizontal < options.min_angle_from_horizontal_rad) continue;
    const float l_lo = std::min(l.start.y(), l.end.y()), l_hi = std::max(l.start.y(), l.end.y());
    float best = std::numeric_limits<float>::infinity();
    int best_j = -1;
    for (size_t j = 0; j < right.size(); ++j) {
      const LineSegment& r = right[j];
      if (AngleDifference(l.Angle(), r.Angle()) > options.max_angle_rad) continue;
      const float r_lo = std::min(r.start.y(), r.end.y()), r_hi = std::max(r.start.y(), r.end.y());
      const float overlap = std::min(l_hi, r_hi) - std::max(l_lo, r_lo);
      const float shorter = std::max(1.0f, std::min(l_hi - l_lo, r_hi - r_lo));
      if (overlap / shorter < options.min_row_overlap) continue;
      const float disparity = 0.5f * (l.start.x() + l.end.x() - r.start.x() - r.end.x());
      if (disparity < options.min_disparity_px) continue;
      const float d = LbdDistance(lbd_left, static_cast<int>(i), lbd_right, static_cast<int>(j));
      if (d < best && d <= options.max_lbd_distance) {
        best = d;
        best_j = static_cast<int>(j);
      }
    }
    if (best_j >= 0) candidates.push_back({best, {static_cast<int>(i), best_j}});
  }
  return UniqueByCost(candidates);
}

bool TriangulateStereoLine(const LineSegment& left, const LineSegment& right,
                           const PinholeCamera& camera, double baseline_m,
                           Eigen::Vector3d* start_in_cam, Eigen::Vector3d* end_in_cam,
                           float min_disparity_px) {
  const float dv = right.end.y() - right.start.y();
  if (std::abs(dv) < 1e-3f) return false;  // horizontal: rows do not pin the endpoints
  Eigen::Vector3d points[2];
  int k = 0;
  for (const Eigen::Vector2f& p : {left.start, left.end}) {
    const float t = (p.y() - right.start.y()) / dv;
    const float u_right = right.start.x() + t * (right.end.x() - right.start.x());
    const double disparity = p.x() - u_right;
    if (disparity < min_disparity_px) return false;
    const double z = camera.fx * baseline_m / disparity;
    points[k++] = Eigen::Vector3d((p.x() - camera.cx) / camera.fx * z,
                                  (p.y() - camera.cy) / camera.fy * z, z);
  }
  *start_in_cam = points[0];
  *end_in_cam = points[1];
  return true;
}

}  // namespace slslam
