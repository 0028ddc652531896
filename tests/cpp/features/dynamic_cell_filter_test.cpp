#include "slslam/features/dynamic_cell_filter.h"

#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace slslam {
namespace {

using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

const PinholeCamera kCamera{458.0, 458.0, 375.5, 239.5, 752, 480};

PixelArray Project(const Points& points, const Eigen::Isometry3d& T) {
  PixelArray uv(points.rows(), 2);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector2d p = kCamera.Project(T * Eigen::Vector3d(points.row(i)));
    uv.row(i) = p.cast<float>().transpose();
  }
  return uv;
}

// A static scene seen from a moving camera, with one block of points (a walking worker) in the
// image region u in [300, 420), v in [180, 300) that moves 0.25 m sideways between the frames.
struct Scene {
  Points previous;       // points in the previous camera frame
  Points current_world;  // the same points at the current time (block moved)
  std::vector<bool> in_block;
};

Scene MakeScene() {
  cv::RNG rng(11);
  Scene s;
  const int n = 1500;
  s.previous.resize(n, 3);
  s.in_block.assign(n, false);
  for (int i = 0; i < n; ++i) {
    const bool block = i < 150;
    const double u = block ? rng.uniform(300.0, 420.0) : rng.uniform(0.0, 752.0);
    const double v = block ? rng.uniform(180.0, 300.0) : rng.uniform(0.0, 480.0);
    const double z = block ? rng.uniform(3.8, 4.2) : rng.uniform(3.0, 12.0);
    s.previous.row(i) = kCamera.Unproject({u, v}).transpose() * z;
    s.in_block[i] = block;
  }
  s.current_world = s.previous;
  for (int i = 0; i < 150; ++i) s.current_world(i, 0) += 0.25;
  return s;
}

Eigen::Isometry3d CameraMotion() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.02, 0.0, -0.15);  // forward 15 cm, turning
  return T;
}

TEST(DynamicCellFilter, RobustPoseFlagsOnlyTheMovingBlock) {
  const Scene scene = MakeScene();
  const Eigen::Isometry3d T_cur_prev = CameraMotion();
  const PixelArray observed = Project(scene.current_world, T_cur_prev);
  const RobustPrediction robust = PredictWithRobustPose(scene.previous, observed, kCamera);
  ASSERT_TRUE(robust.ok);
  EXPECT_TRUE(robust.T_cur_prev.isApprox(T_cur_prev.matrix(), 1e-4));

  DynamicCellOptions options;
  DynamicCellFilter filter(752, 480, options);
  for (int frame = 0; frame < 3; ++frame) filter.Update(observed, robust.predicted);
  const std::vector<bool> mask = filter.KeypointMask(observed);
  // Where the block is seen now; cells within one cell (+ the cell itself) of it may go.
  Eigen::Array2f lo(1e9f, 1e9f), hi(-1e9f, -1e9f);
  for (Eigen::Index i = 0; i < observed.rows(); ++i) {
    if (!scene.in_block[i]) continue;
    lo = lo.min(observed.row(i).transpose().array());
    hi = hi.max(observed.row(i).transpose().array());
  }
  const float margin = 2.0f * options.cell_size_px;
  int block_kept = 0, static_dropped = 0, static_far = 0;
  for (Eigen::Index i = 0; i < observed.rows(); ++i) {
    if (scene.in_block[i]) {
      block_kept += mask[i];
      continue;
    }
    // Static points more than one cell (plus the motion) away from the block stay valid.
    const float u = observed(i, 0), v = observed(i, 1);
    const bool far =
        u < lo.x() - margin || u > hi.x() + margin || v < lo.y() - margin || v > hi.y() + margin;
    if (far && u >= 0 && v >= 0 && u < 752 && v < 480) {
      ++static_far;
      static_dropped += !mask[i];
    }
  }
  EXPECT_EQ(block_kept, 0);
  EXPECT_GT(static_far, 800);
  EXPECT_EQ(static_dropped, 0);
}

TEST(DynamicCellFilter, ConstantVelocityPredictionWithAWrongMotionFlagsStaticCells) {
  // The paper's variant: predicting with last frame's motion (here: standing still) while the
  // camera turned flags static cells too. This is why the robust pose is used above.
  const Scene scene = MakeScene();
  const PixelArray observed = Project(scene.current_world, CameraMotion());
  const PixelArray constant_velocity = Project(scene.previous, Eigen::Isometry3d::Identity());
  DynamicCellOptions options;
  options.sigma_median_ratio = 0.0;  // the paper's fixed width (the default)
  DynamicCellFilter filter(752, 480, options);
  filter.Update(observed, constant_velocity);
  int invalid = 0;
  for (bool v : filter.valid()) invalid += !v;
  EXPECT_GT(invalid, static_cast<int>(filter.valid().size()) / 2);
}

TEST(DynamicCellFilter, TemporalSmoothingNeedsRepeatedEvidence) {
  DynamicCellOptions options;
  options.alpha = 0.3;  // a single bad frame moves the weight only by 30 %
  options.min_matches = 1;
  options.sigma_median_ratio = 0.0;  // the default: a fixed width
  DynamicCellFilter filter(64, 64, options);
  PixelArray observed(1, 2), predicted(1, 2);
  observed << 10, 10;
  predicted << 30, 10;  // 20 px off: G(d) ~ 0
  filter.Update(observed, predicted);
  EXPECT_NEAR(filter.weights()[0], 0.7, 1e-6);
  EXPECT_TRUE(filter.valid()[0]);
  filter.Update(observed, predicted);
  filter.Update(observed, predicted);
  EXPECT_LT(filter.weights()[0], 0.5);
  EXPECT_FALSE(filter.valid()[0]);
  EXPECT_FALSE(filter.valid()[1]);  // the neighbour goes with it
  EXPECT_FALSE(filter.valid()[3]);  // diagonal neighbour (2 x 2 cells)
  EXPECT_THROW(filter.Update(observed, PixelArray(2, 2)), std::invalid_argument);
}

TEST(DynamicCellFilter, ACellWithoutMatchesRecovers) {
  // The mover has left: no match falls in the cell any more, so nothing disagrees with the
  // motion and the weight climbs back (alpha 0.7: 0.7 + 0.3 w per frame) until the cell is valid.
  DynamicCellOptions options;
  options.min_matches = 1;
  options.sigma_median_ratio = 0.0;  // the default: a fixed width
  DynamicCellFilter filter(64, 64, options);
  PixelArray observed(1, 2), predicted(1, 2);
  observed << 10, 10;
  predicted << 40, 10;  // 30 px off
  filter.Update(observed, predicted);
  filter.Update(observed, predicted);
  ASSERT_FALSE(filter.valid()[0]);
  filter.Update(PixelArray(0, 2), PixelArray(0, 2));
  EXPECT_TRUE(filter.valid()[0]);        // 0.3 * 0.09 + 0.7 = 0.73 >= 0.5
  EXPECT_GT(filter.weights()[1], 0.99);  // a cell that never had matches stays at 1
}

TEST(DynamicCellFilter, OneMatchIsNoEvidenceAndAMedianIgnoresAMismatch) {
  DynamicCellOptions options;        // min_matches 2
  options.sigma_median_ratio = 0.0;  // the default: a fixed width
  DynamicCellFilter filter(64, 64, options);
  PixelArray one(1, 2), one_predicted(1, 2);
  one << 10, 10;
  one_predicted << 40, 10;  // 30 px off, but alone in its cell
  for (int k = 0; k < 5; ++k) filter.Update(one, one_predicted);
  EXPECT_TRUE(filter.valid()[0]);
  // Three matches, one of them 30 px off (a mismatch): the median is 0.5 px, the cell stays.
  PixelArray three(3, 2), three_predicted(3, 2);
  three << 10, 10, 12, 12, 14, 14;
  three_predicted << 10.5, 10, 12.5, 12, 44, 14;
  for (int k = 0; k < 5; ++k) filter.Update(three, three_predicted);
  EXPECT_TRUE(filter.valid()[0]);
  // All three displaced 10 px (a mover): invalid after two frames.
  three_predicted << 20, 10, 22, 12, 24, 14;
  filter.Update(three, three_predicted);
  filter.Update(three, three_predicted);
  EXPECT_FALSE(filter.valid()[0]);
}

TEST(DynamicCellFilter, NoisyMatchesWidenTheGaussianAndTheMoverStillStandsOut) {
  // A front end whose keypoints repeat less precisely (XFeat on the simulated loop: a median
  // frame-to-frame residual of about 2 px, ORB's 1 px): static matches off by 1-4 px at random,
  // and one cell's matches (a mover) all 15 px off. The fixed width (sigma 3 px) flags static
  // cells; sigma_median_ratio 3 widens G to about 3x the frame's median and flags the mover only.
  cv::RNG rng(5);
  const int width = 768, height = 480;  // whole 32 px cells
  const int cells_x = width / 32, cells_y = height / 32;
  const int mover = 7 * cells_x + 11;  // the cell at (11, 7)
  std::vector<Eigen::Vector2f> obs, pred;
  for (int c = 0; c < cells_x * cells_y; ++c) {
    const float u0 = static_cast<float>(c % cells_x) * 32.0f;
    const float v0 = static_cast<float>(c / cells_x) * 32.0f;
    for (int k = 0; k < 6; ++k) {
      const Eigen::Vector2f p(u0 + rng.uniform(2.0f, 30.0f), v0 + rng.uniform(2.0f, 30.0f));
      const float d = c == mover ? 15.0f : rng.uniform(1.0f, 4.0f);
      const float angle = rng.uniform(0.0f, 6.2831853f);
      obs.push_back(p);
      pred.push_back(p + d * Eigen::Vector2f(std::cos(angle), std::sin(angle)));
    }
  }
  PixelArray observed(obs.size(), 2), predicted(pred.size(), 2);
  for (size_t i = 0; i < obs.size(); ++i) {
    observed.row(i) = obs[i].transpose();
    predicted.row(i) = pred[i].transpose();
  }
  auto invalid_cells = [&](double ratio) {
    DynamicCellOptions options;
    options.sigma_median_ratio = ratio;
    DynamicCellFilter filter(width, height, options);
    for (int frame = 0; frame < 3; ++frame) filter.Update(observed, predicted);
    std::vector<int> invalid;
    for (size_t c = 0; c < filter.valid().size(); ++c) {
      if (!filter.valid()[c]) invalid.push_back(static_cast<int>(c));
    }
    return std::make_pair(invalid, filter.weights()[mover]);
  };
  const auto [fixed, fixed_mover_weight] = invalid_cells(0.0);
  EXPECT_GT(fixed.size(), 9u);  // static cells flagged besides the mover and its neighbours
  const auto [widened, mover_weight] = invalid_cells(3.0);
  EXPECT_LT(mover_weight, 0.5);
  ASSERT_EQ(widened.size(), 9u);  // the mover and its 8 neighbours, nothing else
  for (int c : widened) {
    EXPECT_LE(std::abs(c % cells_x - 11), 1);
    EXPECT_LE(std::abs(c / cells_x - 7), 1);
  }
  DynamicCellOptions bad;
  bad.sigma_median_ratio = -1.0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
