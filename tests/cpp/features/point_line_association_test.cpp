#include "slslam/features/point_line_association.h"

#include <stdexcept>

#include <gtest/gtest.h>

namespace slslam {
namespace {

TEST(AssociatePointsToLines, PointsOnTheSegmentOnlyAndOnlyInValidCells) {
  // A horizontal line from (40, 100) to (200, 100) and a vertical one from (300, 20) to (300, 200).
  const Segments lines = {{{40, 100}, {200, 100}}, {{300, 20}, {300, 200}}};
  PixelArray keypoints(7, 2);
  keypoints << 50, 101,  // 0: on line 0
      190, 99.2f,        // 1: on line 0
      120, 104,          // 2: 4 px off line 0: too far
      230, 100,          // 3: 30 px beyond line 0's end: outside its u-range, inside its v-range
      301, 150,          // 4: on line 1
      300, 260,          // 5: 60 px beyond line 1's end: outside its extended cell region
      100, 300;          // 6: nowhere near
  const auto assoc = AssociatePointsToLines(keypoints, lines, 640, 480);
  ASSERT_EQ(assoc.size(), 2u);
  // The paper's projection test is "u within the u-range OR v within the v-range": keypoint 3
  // passes through the v-range of a horizontal line; the extended region still bounds it.
  EXPECT_EQ(assoc[0], (std::vector<int>{0, 1, 3}));
  EXPECT_EQ(assoc[1], (std::vector<int>{4}));
  // The dynamic-cell filter invalidated the cell of keypoint 0 (u 50, v 101 -> cell (1, 3)).
  std::vector<bool> valid(20 * 15, true);
  valid[3 * 20 + 1] = false;
  const auto filtered = AssociatePointsToLines(keypoints, lines, 640, 480, {}, valid);
  EXPECT_EQ(filtered[0], (std::vector<int>{1, 3}));
}

TEST(AssociatePointsToLines, RejectsBadInput) {
  AssociationOptions bad;
  bad.layers = -1;
  EXPECT_THROW(AssociatePointsToLines(PixelArray(0, 2), {}, 64, 64, bad), std::invalid_argument);
  EXPECT_THROW(AssociatePointsToLines(PixelArray(0, 2), {}, 64, 64, {}, {true}),
               std::invalid_argument);
}

}  // namespace
}  // namespace slslam
