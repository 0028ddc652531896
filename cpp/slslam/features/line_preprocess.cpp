#include "slslam/features/line_preprocess.h"

#include <algorithm>
#include <limits>
#include <numeric>

#include "slslam/core/check.h"

namespace slslam {

void LinePreprocessOptions::Check() const {
  SLSLAM_CHECK(length_ratio > 0.0f && length_ratio < 1.0f,
               "lines.length_ratio must be in (0, 1), got ", length_ratio);
  CheckAboveInRange("lines.theta_min_rad", theta_min_rad, 0.0f, limits::kPi);
  CheckAboveInRange("lines.xi_d_px", xi_d_px, 0.0f, limits::kMaxImageDistancePx);
  // infinity allowed: the paper's rule without a gap limit
  CheckInRange("lines.max_gap_px", max_gap_px, 0.0f, std::numeric_limits<float>::infinity());
}

float AngleGateFactor(float candidate_length, float length_threshold) {
  const float lambda = candidate_length / length_threshold;
  return 1.0f - 1.0f / (1.0f + std::exp(-4.0f * lambda + 5.0f));
}

namespace {

// Gap between the two segments' extents along the source direction (0 when they overlap) [px].
float GapAlong(const LineSegment& source, const LineSegment& candidate) {
  const Eigen::Vector2f d = (source.end - source.start).normalized();
  const float s0 = 0.0f, s1 = (source.end - source.start).dot(d);
  const float c0 = (candidate.start - source.start).dot(d);
  const float c1 = (candidate.end - source.start).dot(d);
  const float lo = std::min(c0, c1), hi = std::max(c0, c1);
  return std::max({0.0f, lo - s1, s0 - hi});
}

// The source extended to the outermost projections of both segments' endpoints on its line.
LineSegment Merge(const LineSegment& source, const LineSegment& candidate) {
  const Eigen::Vector2f d = (source.end - source.start).normalized();
  float lo = 0.0f, hi = (source.end - source.start).dot(d);
  for (const Eigen::Vector2f& p : {candidate.start, candidate.end}) {
    const float t = (p - source.start).dot(d);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  return {source.start + lo * d, source.start + hi * d};
}

}  // namespace

Segments PreprocessLines(const Segments& segments, int width, int height,
                         const LinePreprocessOptions& options) {
  options.Check();
  SLSLAM_CHECK(width > 0 && height > 0, "image size must be positive, got ", width, "x", height);
  const float length_threshold = std::min(width, height) * options.length_ratio;
  Segments sorted;
  for (const LineSegment& s : segments) {
    if (s.start.allFinite() && s.end.allFinite() && s.Length() > length_threshold) {
      sorted.push_back(s);
    }
  }
  std::stable_sort(sorted.begin(), sorted.end(), [](const LineSegment& a, const LineSegment& b) {
    return a.Length() > b.Length();
  });
  // Each candidate's angle and angle gate once, not once per pair (an arctangent, a square root and
  // an exponential in the inner loop were most of this function's time); the source's angle once
  // and again after each merge. The same values as computed per pair, so the same segments.
  std::vector<float> angle(sorted.size()), angle_bound(sorted.size());
  for (size_t j = 0; j < sorted.size(); ++j) {
    angle[j] = sorted[j].Angle();
    angle_bound[j] = AngleGateFactor(sorted[j].Length(), length_threshold) * options.theta_min_rad;
  }
  std::vector<bool> removed(sorted.size(), false);
  Segments out;
  for (size_t i = 0; i < sorted.size(); ++i) {
    if (removed[i]) continue;
    LineSegment source = sorted[i];
    float source_angle = angle[i];
    for (size_t j = i + 1; j < sorted.size(); ++j) {
      if (removed[j]) continue;
      const LineSegment& candidate = sorted[j];
      if (AngleDifference(source_angle, angle[j]) >= angle_bound[j]) continue;
      if (GapAlong(source, candidate) > options.max_gap_px) continue;
      const float D =
          0.25f * (candidate.DistanceToLine(source.start) + candidate.DistanceToLine(source.end) +
                   source.DistanceToLine(candidate.start) + source.DistanceToLine(candidate.end));
      if (D < options.xi_d_px) {
        source = Merge(source, candidate);
        source_angle = source.Angle();
        removed[j] = true;
      } else if (D < 3.0f * options.xi_d_px) {
        removed[j] = true;  // redundant near-duplicate
      }
    }
    out.push_back(source);
  }
  std::stable_sort(out.begin(), out.end(), [](const LineSegment& a, const LineSegment& b) {
    return a.Length() > b.Length();
  });
  return out;
}

}  // namespace slslam
