// Local mapping's epipolar candidates: the prefilter must return every keypoint an exhaustive
// scan finds within the band, in ascending order, for lines of every direction (exactly horizontal
// and vertical ones included) and keypoints outside the image, and leave most others out.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "slslam/mapping/triangulation.h"

namespace slslam {
namespace {

using triangulation_detail::EpipolarCandidates;
using Positions = Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>;

std::vector<int> Exhaustive(const Positions& uv, const std::vector<int>& ids,
                            const Eigen::Vector3d& line, double band) {
  std::vector<int> out;
  for (int id : ids) {
    const double d = std::abs(line.x() * uv(id, 0) + line.y() * uv(id, 1) + line.z());
    if (d <= band) out.push_back(id);
  }
  return out;
}

TEST(EpipolarCandidates, HoldEveryKeypointInTheBandInAscendingOrder) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-40.0f, 800.0f), v(-30.0f, 520.0f);
  Positions uv(900, 2);
  for (int i = 0; i < uv.rows(); ++i) uv.row(i) << u(rng), v(rng);
  uv.row(5) << 0.0f, 0.0f;
  uv.row(7) = uv.row(8);  // two at one position
  std::vector<int> ids;
  for (int i = 0; i < uv.rows(); i += (i % 3 == 0 ? 2 : 1)) ids.push_back(i);
  EpipolarCandidates prefilter(uv, ids);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * M_PI), offset(-900.0, 900.0);
  std::vector<double> angles = {0.0, M_PI / 2, M_PI, 1.5 * M_PI, 1e-12, M_PI / 2 + 1e-12};
  for (int k = 0; k < 400; ++k) angles.push_back(angle(rng));
  size_t collected = 0, total = 0;
  std::vector<int> candidates;
  for (double a : angles) {
    for (double band : {0.0, 2.5, 7.0}) {
      // Through a keypoint (the band then holds at least that one) or anywhere.
      const Eigen::Vector2d n(std::cos(a), std::sin(a));
      const int through = ids[static_cast<size_t>(std::abs(offset(rng))) % ids.size()];
      for (double c : {-(n.x() * uv(through, 0) + n.y() * uv(through, 1)), offset(rng)}) {
        const Eigen::Vector3d line(n.x(), n.y(), c);
        prefilter.Collect(line, band, &candidates);
        ASSERT_TRUE(std::is_sorted(candidates.begin(), candidates.end()));
        ASSERT_EQ(std::adjacent_find(candidates.begin(), candidates.end()), candidates.end());
        for (int id : Exhaustive(uv, ids, line, band)) {
          ASSERT_TRUE(std::binary_search(candidates.begin(), candidates.end(), id))
              << "keypoint " << id << " missing for angle " << a << ", band " << band;
        }
        for (int id : candidates) {
          ASSERT_TRUE(std::binary_search(ids.begin(), ids.end(), id)) << "not one of the given ids";
        }
        collected += candidates.size();
        total += ids.size();
      }
    }
  }
  // The point of the prefilter: a line's band holds a small share of the keypoints.
  EXPECT_LT(collected, total / 5);
}

TEST(EpipolarCandidates, SkipNonFinitePositionsAndEmptySets) {
  Positions uv(3, 2);
  uv << 10.0f, 10.0f, std::numeric_limits<float>::quiet_NaN(), 5.0f, 1e7f, -1e7f;
  EpipolarCandidates prefilter(uv, {0, 1, 2});
  std::vector<int> candidates = {42};
  prefilter.Collect(Eigen::Vector3d(1.0, 0.0, -10.0), 1.0, &candidates);  // u = 10
  EXPECT_EQ(candidates, std::vector<int>({0}));
  prefilter.Collect(Eigen::Vector3d(0.0, 1.0, 1e7), 1.0, &candidates);  // v = -1e7
  EXPECT_EQ(candidates, std::vector<int>({2}));
  EpipolarCandidates empty(uv, {});
  empty.Collect(Eigen::Vector3d(1.0, 0.0, -10.0), 1.0, &candidates);
  EXPECT_TRUE(candidates.empty());
}

}  // namespace
}  // namespace slslam
