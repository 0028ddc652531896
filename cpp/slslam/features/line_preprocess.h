// Line preprocessing (the SL-SLAM paper's): long segments first; short, fragmented and duplicated
// LSD segments are merged into or deleted against longer "source" segments.
#pragma once

#include "slslam/features/line_segment.h"

namespace slslam {

struct LinePreprocessOptions {
  float length_ratio = 0.05f;  ///< zeta: keep segments longer than min(H, W) * zeta [-]
  float theta_min_rad = static_cast<float>(M_PI / 90.0);  ///< angle unit of the gate [rad]
  float xi_d_px = 2.0f;  ///< xi_d: merge below, delete below 3 xi_d, else independent [px];
                         ///< the paper leaves the value open
  // Largest gap along the source direction between a candidate and the source [px]. The paper has
  // no such limit, so collinear segments on opposite sides of the image would merge into one
  // line through empty space; infinity restores the paper's rule.
  float max_gap_px = 20.0f;

  void Check() const;
};

// The SL-SLAM paper's angle gate: delta = 1 - 1 / (1 + exp(-4 lambda + 5)), lambda = length / l.
float AngleGateFactor(float candidate_length, float length_threshold);

// Preprocesses LSD segments of a width x height image. Returns the kept segments, longest first.
// For each source (longest first) the candidates are the remaining segments with
// |theta_s - theta_c| < delta * theta_min; for a candidate, D is the mean of the four distances of
// each segment's endpoints to the other's line. D < xi_d: merged (the source grows to the outermost
// projections of all four endpoints on its line); xi_d <= D < 3 xi_d: deleted as redundant;
// D >= 3 xi_d: independent, it stays and becomes a source itself later.
Segments PreprocessLines(const Segments& segments, int width, int height,
                         const LinePreprocessOptions& options = {});

}  // namespace slslam
