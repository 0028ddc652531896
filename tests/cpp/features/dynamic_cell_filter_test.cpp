#include "slslam/features/dynamic_cell_filter.h"

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
  DynamicCellFilter filter(752, 480);
  filter.Update(observed, constant_velocity);
  int invalid = 0;
  for (bool v : filter.valid()) invalid += !v;
  EXPECT_GT(invalid, static_cast<int>(filter.valid().size()) / 2);
}

TEST(DynamicCellFilter, TemporalSmoothingNeedsRepeatedEvidence) {
  DynamicCellOptions options;
  options.alpha = 0.3;  // a single bad frame moves the weight only by 30 %
  options.min_matches = 1;
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
  DynamicCellFilter filter(64, 64);  // min_matches 2
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

}  // namespace
}  // namespace slslam
