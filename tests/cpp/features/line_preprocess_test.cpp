#include "slslam/features/line_preprocess.h"

#include <stdexcept>

#include <gtest/gtest.h>

namespace slslam {
namespace {

// 640 x 480 image: length threshold l = 480 * 0.05 = 24 px.
constexpr int kW = 640, kH = 480;

LineSegment Seg(float u0, float v0, float u1, float v1) { return {{u0, v0}, {u1, v1}}; }

TEST(PreprocessLines, DropsShortSegmentsAndSortsByLength) {
  const Segments out =
      PreprocessLines({Seg(0, 0, 20, 0), Seg(0, 100, 50, 100), Seg(0, 200, 200, 200)}, kW, kH);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_FLOAT_EQ(out[0].Length(), 200.0f);
  EXPECT_FLOAT_EQ(out[1].Length(), 50.0f);
}

TEST(PreprocessLines, MergesCollinearFragmentsIntoTheSource) {
  // Source 100 px; a 26 px fragment on the same line after a 5 px gap, 0.5 px off: D < xi_d.
  const Segments out =
      PreprocessLines({Seg(100, 100, 200, 100), Seg(205, 100.5f, 231, 100.5f)}, kW, kH);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(out[0].start.x(), 100.0f, 1e-4);
  EXPECT_NEAR(out[0].end.x(), 231.0f, 1e-4);
  EXPECT_NEAR(out[0].end.y(), 100.0f, 1e-4);  // the source's line is kept
}

TEST(PreprocessLines, DeletesNearDuplicatesAndKeepsIndependentParallels) {
  // 4 px off (xi_d <= D < 3 xi_d): redundant, deleted. 10 px off: independent, kept.
  const Segments deleted =
      PreprocessLines({Seg(100, 100, 200, 100), Seg(120, 104, 146, 104)}, kW, kH);
  EXPECT_EQ(deleted.size(), 1u);
  EXPECT_FLOAT_EQ(deleted[0].Length(), 100.0f);  // deleting does not extend the source
  const Segments kept = PreprocessLines({Seg(100, 100, 200, 100), Seg(120, 110, 146, 110)}, kW, kH);
  EXPECT_EQ(kept.size(), 2u);
}

TEST(PreprocessLines, AngleGateAndGapLimitKeepOtherLines) {
  // Crossing at 45 deg: outside the angle gate, both kept.
  EXPECT_EQ(PreprocessLines({Seg(100, 100, 200, 100), Seg(140, 80, 166, 106)}, kW, kH).size(), 2u);
  // Collinear but 300 px apart: the gap limit keeps them apart (the paper would merge them).
  EXPECT_EQ(PreprocessLines({Seg(0, 50, 100, 50), Seg(400, 50, 426, 50)}, kW, kH).size(), 2u);
  LinePreprocessOptions paper;
  paper.max_gap_px = std::numeric_limits<float>::infinity();
  EXPECT_EQ(PreprocessLines({Seg(0, 50, 100, 50), Seg(400, 50, 426, 50)}, kW, kH, paper).size(),
            1u);
}

TEST(PreprocessLines, AngleGateFollowsTheSigmoid) {
  // delta = 1 - 1 / (1 + exp(-4 lambda + 5)): lambda = 1 -> 0.731, lambda = 1.25 -> 0.5.
  EXPECT_NEAR(AngleGateFactor(24.0f, 24.0f), 0.7311f, 1e-4);
  EXPECT_NEAR(AngleGateFactor(30.0f, 24.0f), 0.5f, 1e-6);
  EXPECT_LT(AngleGateFactor(96.0f, 24.0f), 1e-4f);
}

TEST(PreprocessLines, RejectsBadOptions) {
  LinePreprocessOptions bad;
  bad.xi_d_px = 0.0f;
  EXPECT_THROW(PreprocessLines({}, kW, kH, bad), std::invalid_argument);
  EXPECT_THROW(PreprocessLines({}, 0, kH), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
