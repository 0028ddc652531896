// The Ceres costs, seen through their manifolds the way Ceres sees them (J_ambient * PlusJacobian),
// against central differences of residual(Plus(x, delta)).
#include "slslam/optimization/cost_functions.h"

#include <array>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "../test_support.h"
#include "check_cost.h"
#include "slslam/geometry/rotation.h"
#include "slslam/optimization/manifolds.h"

namespace slslam {
namespace {

using test::CheckCost;
using test::EurocLikeRig;
using test::RowMatrix;

std::vector<double> PoseParams() {
  std::vector<double> p(kPoseSize);
  PoseToParameters(
      Rigid3d(ExpSO3(Eigen::Vector3d(0.1, -0.3, 0.2)), Eigen::Vector3d(0.3, -0.1, 0.5)), p.data());
  return p;
}

TEST(CostFunctions, PointCostJacobiansThroughManifold) {
  const StereoRig rig = EurocLikeRig();
  PointCost cost(rig.camera, Eigen::Vector2d(300.0, 200.0), 1.5);
  PoseManifold pose_manifold;
  CheckCost(cost, {PoseParams(), {0.4, -0.2, 5.0}}, {&pose_manifold, nullptr});
}

TEST(CostFunctions, StereoPointCostJacobiansThroughManifold) {
  const StereoRig rig = EurocLikeRig();
  StereoPointCost cost(rig, Eigen::Vector3d(300.0, 200.0, 290.0), 1.0);
  PoseManifold pose_manifold;
  CheckCost(cost, {PoseParams(), {0.4, -0.2, 5.0}}, {&pose_manifold, nullptr});
}

// Bundle adjustment gives each stereo observation as two 2-row halves (Ceres' fixed-size Schur
// kernel): StereoPointCost's rows plus a zero row, with the derivatives of what they return.
TEST(CostFunctions, StereoPointHalvesAreTheStereoCostsRows) {
  const StereoRig rig = EurocLikeRig();
  const std::vector<double> pose = PoseParams();
  const std::vector<double> point = {0.4, -0.2, 5.0};
  const double* parameters[2] = {pose.data(), point.data()};
  const Eigen::Vector3d observed(300.0, 200.0, 290.0);
  const double sigma_px = 1.5;
  const StereoPointCost whole(rig, observed, sigma_px);
  Eigen::Vector3d e;
  RowMatrix d_pose(3, kPoseSize), d_point(3, 3);
  double* whole_jacobians[2] = {d_pose.data(), d_point.data()};
  ASSERT_TRUE(whole.Evaluate(parameters, e.data(), whole_jacobians));
  PoseManifold pose_manifold;
  for (int half = 0; half < 2; ++half) {
    const StereoPointHalfCost cost(rig, observed, sigma_px, half);
    CheckCost(cost, {pose, point}, {&pose_manifold, nullptr});
    Eigen::Vector2d r;
    RowMatrix h_pose(2, kPoseSize), h_point(2, 3);
    double* jacobians[2] = {h_pose.data(), h_point.data()};
    ASSERT_TRUE(cost.Evaluate(parameters, r.data(), jacobians));
    const int row = half == 0 ? 0 : 2;
    EXPECT_EQ(r(0), e(row));
    EXPECT_EQ(h_pose.row(0), d_pose.row(row));
    EXPECT_EQ(h_point.row(0), d_point.row(row));
    if (half == 0) {
      EXPECT_EQ(r(1), e(1));
      EXPECT_EQ(h_pose.row(1), d_pose.row(1));
      EXPECT_EQ(h_point.row(1), d_point.row(1));
    } else {
      EXPECT_EQ(r(1), 0.0);
      EXPECT_TRUE(h_pose.row(1).isZero(0.0));
      EXPECT_TRUE(h_point.row(1).isZero(0.0));
    }
  }
  EXPECT_THROW(StereoPointHalfCost(rig, observed, sigma_px, 2), std::invalid_argument);
}

TEST(CostFunctions, LineCostJacobiansThroughManifold) {
  const StereoRig rig = EurocLikeRig();
  LineCost cost(rig.camera, Eigen::Vector2d(250.0, 210.0), Eigen::Vector2d(420.0, 285.0), 10.0,
                1.0);
  std::vector<double> line(kLineSize);
  LineToParameters(OrthonormalLine::FromPlucker(PluckerLine::FromPoints(
                       Eigen::Vector3d(-0.8, 0.4, 6.0), Eigen::Vector3d(0.9, -0.3, 7.5))),
                   line.data());
  PoseManifold pose_manifold;
  LineManifold line_manifold;
  CheckCost(cost, {PoseParams(), line}, {&pose_manifold, &line_manifold});
}

std::vector<double> LineParams(const PluckerLine& line) {
  std::vector<double> p(kLineSize);
  LineToParameters(OrthonormalLine::FromPlucker(line), p.data());
  return p;
}

TEST(CostFunctions, AnchoredLineCostJacobiansThroughManifold) {
  const StereoRig rig = EurocLikeRig();
  const Eigen::Vector3d anchor(2.0, -1.0, 30.0);  // far from the line and from the origin
  LineCost cost(rig.camera, Eigen::Vector2d(250.0, 210.0), Eigen::Vector2d(420.0, 285.0), 10.0, 1.0,
                anchor);
  const PluckerLine world =
      PluckerLine::FromPoints(Eigen::Vector3d(-0.8, 0.4, 6.0), Eigen::Vector3d(0.9, -0.3, 7.5));
  PluckerLine local = world;
  local.n -= anchor.cross(local.v);
  PoseManifold pose_manifold;
  LineManifold line_manifold;
  CheckCost(cost, {PoseParams(), LineParams(local)}, {&pose_manifold, &line_manifold});

  // The same residual as the world line given to an unanchored cost.
  LineCost plain(rig.camera, Eigen::Vector2d(250.0, 210.0), Eigen::Vector2d(420.0, 285.0), 10.0,
                 1.0);
  const std::vector<double> pose = PoseParams();
  const std::vector<double> anchored_line = LineParams(local), world_line = LineParams(world);
  const double* a[] = {pose.data(), anchored_line.data()};
  const double* b[] = {pose.data(), world_line.data()};
  Eigen::Vector3d ra, rb;
  ASSERT_TRUE(cost.Evaluate(a, ra.data(), nullptr));
  ASSERT_TRUE(plain.Evaluate(b, rb.data(), nullptr));
  EXPECT_LT((ra - rb).cwiseAbs().maxCoeff(), 1e-9) << ra.transpose() << " / " << rb.transpose();
}

TEST(CostFunctions, LinePriorCostHoldsTheLine) {
  const std::vector<double> reference = LineParams(
      PluckerLine::FromPoints(Eigen::Vector3d(-0.8, 0.4, 6.0), Eigen::Vector3d(0.9, -0.3, 7.5)));
  LinePriorCost cost(reference.data(), 30.0);
  LineManifold line_manifold;
  // At the reference: zero residual, and the tangent Jacobian is weight * identity.
  CheckCost(cost, {reference}, {&line_manifold});
  const double* at[] = {reference.data()};
  Eigen::Vector4d r;
  ASSERT_TRUE(cost.Evaluate(at, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-12);
  // A step away costs weight * its length in the tangent.
  const Eigen::Vector4d step(0.01, -0.02, 0.005, 0.003);
  std::vector<double> moved(kLineSize);
  line_manifold.Plus(reference.data(), step.data(), moved.data());
  const double* away[] = {moved.data()};
  ASSERT_TRUE(cost.Evaluate(away, r.data(), nullptr));
  EXPECT_LT((r - 30.0 * step).cwiseAbs().maxCoeff(), 1e-9) << r.transpose();
}

TEST(Manifolds, MinusInvertsPlus) {
  PoseManifold pose_manifold;
  const std::vector<double> x = PoseParams();
  const std::array<double, 6> delta{0.1, -0.2, 0.3, 0.05, -0.1, 0.2};
  std::array<double, kPoseSize> y;
  std::array<double, 6> back;
  pose_manifold.Plus(x.data(), delta.data(), y.data());
  pose_manifold.Minus(y.data(), x.data(), back.data());
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(back[i], delta[i], 1e-12);

  LineManifold line_manifold;
  std::array<double, kLineSize> l;
  LineToParameters(OrthonormalLine::FromPlucker(PluckerLine::FromPoints(Eigen::Vector3d(1, 2, 3),
                                                                        Eigen::Vector3d(-1, 0, 5))),
                   l.data());
  const std::array<double, 4> dl{0.1, -0.05, 0.2, 0.1};
  std::array<double, kLineSize> l2;
  std::array<double, 4> dl_back;
  line_manifold.Plus(l.data(), dl.data(), l2.data());
  line_manifold.Minus(l2.data(), l.data(), dl_back.data());
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(dl_back[i], dl[i], 1e-12);
}

TEST(Manifolds, LineSubspaceMovesWithinItsSpan) {
  std::array<double, kLineSize> l;
  LineToParameters(OrthonormalLine::FromPlucker(PluckerLine::FromPoints(Eigen::Vector3d(1, 2, 3),
                                                                        Eigen::Vector3d(-1, 0, 5))),
                   l.data());
  // Two orthonormal tangent directions.
  LineSubspaceManifold::Basis basis(4, 2);
  basis.col(0) = Eigen::Vector4d(1, 1, 0, 0).normalized();
  basis.col(1) = Eigen::Vector4d(0, 0, 1, -1).normalized();
  LineSubspaceManifold subspace(basis);
  ASSERT_EQ(subspace.TangentSize(), 2);
  const std::array<double, 2> d{0.1, -0.05};
  std::array<double, kLineSize> moved, full;
  subspace.Plus(l.data(), d.data(), moved.data());
  // The same line as LineManifold's step B d.
  const Eigen::Vector4d step = basis * Eigen::Vector2d(d[0], d[1]);
  LineManifold().Plus(l.data(), step.data(), full.data());
  for (int i = 0; i < kLineSize; ++i) EXPECT_NEAR(moved[i], full[i], 1e-12);
  std::array<double, 2> back;
  subspace.Minus(moved.data(), l.data(), back.data());
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(back[i], d[i], 1e-12);

  // Ceres sees a line cost through it as the cost's tangent Jacobian times B.
  const StereoRig rig = EurocLikeRig();
  LineCost cost(rig.camera, Eigen::Vector2d(250.0, 210.0), Eigen::Vector2d(420.0, 285.0), 10.0,
                1.0);
  const PluckerLine world =
      PluckerLine::FromPoints(Eigen::Vector3d(-0.8, 0.4, 6.0), Eigen::Vector3d(0.9, -0.3, 7.5));
  PoseManifold pose_manifold;
  CheckCost(cost, {PoseParams(), LineParams(world)}, {&pose_manifold, &subspace});
  EXPECT_THROW(LineSubspaceManifold(LineSubspaceManifold::Basis(4, 0)), std::invalid_argument);
}

TEST(CostFunctions, BehindCameraIsNotEvaluated) {
  const StereoRig rig = EurocLikeRig();
  PointCost cost(rig.camera, Eigen::Vector2d(300.0, 200.0), 1.0);
  std::vector<double> pose(kPoseSize);
  PoseToParameters(Rigid3d(), pose.data());
  const double point[3] = {0.0, 0.0, -3.0};
  const double* params[2] = {pose.data(), point};
  double residual[2];
  EXPECT_FALSE(cost.Evaluate(params, residual, nullptr));
  EXPECT_THROW(PointCost(rig.camera, Eigen::Vector2d(1, 1), 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
