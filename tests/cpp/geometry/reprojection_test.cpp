// Analytic Jacobians of the point and line residuals against central differences.
#include "slslam/geometry/reprojection.h"

#include <functional>

#include <gtest/gtest.h>

#include "../test_support.h"
#include "slslam/geometry/rotation.h"

namespace slslam {
namespace {

using test::EurocLikeRig;

struct TestPose {
  Rigid3d cam_from_world{ExpSO3(Eigen::Vector3d(0.1, -0.3, 0.2)), Eigen::Vector3d(0.3, -0.1, 0.5)};
};

using test::ExpectClose;
using test::NumericJacobian;

TEST(PointResidual, JacobiansMatchNumeric) {
  const StereoRig rig = EurocLikeRig();
  const TestPose pose;
  const Eigen::Vector3d point(0.4, -0.2, 5.0);
  const Eigen::Vector2d observed(300.0, 200.0);
  Eigen::Vector2d e;
  Eigen::Matrix<double, 2, 6> d_pose;
  Eigen::Matrix<double, 2, 3> d_point;
  ASSERT_TRUE(
      PointResidual(rig.camera, pose.cam_from_world, point, observed, &e, &d_pose, &d_point));
  ExpectClose(d_pose, NumericJacobian<2>(6, [&](const Eigen::VectorXd& d) {
                Rigid3d perturbed = pose.cam_from_world;
                PerturbPose(d, &perturbed);
                Eigen::Vector2d r;
                PointResidual(rig.camera, perturbed, point, observed, &r);
                return r;
              }));
  ExpectClose(d_point, NumericJacobian<2>(3, [&](const Eigen::VectorXd& d) {
                Eigen::Vector2d r;
                PointResidual(rig.camera, pose.cam_from_world, point + d, observed, &r);
                return r;
              }));
  // Behind the camera: no residual.
  EXPECT_FALSE(
      PointResidual(rig.camera, pose.cam_from_world, Eigen::Vector3d(0, 0, -20), observed, &e));
}

TEST(StereoPointResidual, JacobiansMatchNumericAndRightCoordinateIsDisparity) {
  const StereoRig rig = EurocLikeRig();
  const TestPose pose;
  const Eigen::Vector3d point(0.4, -0.2, 5.0);
  const Eigen::Vector3d x_c = pose.cam_from_world * point;
  const Eigen::Vector2d uv = rig.camera.Project(x_c);
  const Eigen::Vector3d exact(uv.x(), uv.y(), uv.x() - rig.camera.fx * rig.baseline_m / x_c.z());
  Eigen::Vector3d e;
  Eigen::Matrix<double, 3, 6> d_pose;
  Eigen::Matrix<double, 3, 3> d_point;
  ASSERT_TRUE(StereoPointResidual(rig, pose.cam_from_world, point, exact, &e, &d_pose, &d_point));
  EXPECT_LT(e.norm(), 1e-9);
  const Eigen::Vector3d observed = exact + Eigen::Vector3d(1.5, -2.0, 0.7);
  StereoPointResidual(rig, pose.cam_from_world, point, observed, &e, &d_pose, &d_point);
  ExpectClose(d_pose, NumericJacobian<3>(6, [&](const Eigen::VectorXd& d) {
                Rigid3d perturbed = pose.cam_from_world;
                PerturbPose(d, &perturbed);
                Eigen::Vector3d r;
                StereoPointResidual(rig, perturbed, point, observed, &r);
                return r;
              }));
  ExpectClose(d_point, NumericJacobian<3>(3, [&](const Eigen::VectorXd& d) {
                Eigen::Vector3d r;
                StereoPointResidual(rig, pose.cam_from_world, point + d, observed, &r);
                return r;
              }));
}

class LineResidualTest : public ::testing::TestWithParam<double> {};

TEST_P(LineResidualTest, JacobiansMatchNumeric) {
  const double angle_weight = GetParam();
  const StereoRig rig = EurocLikeRig();
  const TestPose pose;
  const PluckerLine line =
      PluckerLine::FromPoints(Eigen::Vector3d(-0.8, 0.4, 6.0), Eigen::Vector3d(0.9, -0.3, 7.5));
  // Observed endpoints off the projected line, so every residual is non-zero.
  const Eigen::Vector2d start(250.0, 210.0);
  const Eigen::Vector2d end(420.0, 285.0);
  Eigen::Vector3d e;
  Eigen::Matrix<double, 3, 6> d_pose;
  Eigen::Matrix<double, 3, 6> d_plucker;
  ASSERT_TRUE(LineResidual(rig.camera, pose.cam_from_world, line, start, end, angle_weight, &e,
                           &d_pose, &d_plucker));
  ExpectClose(d_pose, NumericJacobian<3>(6, [&](const Eigen::VectorXd& d) {
                Rigid3d perturbed = pose.cam_from_world;
                PerturbPose(d, &perturbed);
                Eigen::Vector3d r;
                LineResidual(rig.camera, perturbed, line, start, end, angle_weight, &r);
                return r;
              }));
  ExpectClose(d_plucker, NumericJacobian<3>(6, [&](const Eigen::VectorXd& d) {
                PluckerLine moved = line;
                moved.n += d.head<3>();
                moved.v += d.tail<3>();
                Eigen::Vector3d r;
                LineResidual(rig.camera, pose.cam_from_world, moved, start, end, angle_weight, &r);
                return r;
              }));
  // The 4-DoF chain (what the Ceres cost uses).
  const OrthonormalLine ortho = OrthonormalLine::FromPlucker(line);
  LineResidual(rig.camera, pose.cam_from_world, ortho.ToPlucker(), start, end, angle_weight, &e,
               nullptr, &d_plucker);
  const Eigen::Matrix<double, 3, 4> d_line = d_plucker * ortho.PluckerJacobian();
  ExpectClose(d_line, NumericJacobian<3>(4, [&](const Eigen::VectorXd& d) {
                Eigen::Vector3d r;
                LineResidual(rig.camera, pose.cam_from_world, ortho.Plus(d).ToPlucker(), start, end,
                             angle_weight, &r);
                return r;
              }));
}

INSTANTIATE_TEST_SUITE_P(AngleWeights, LineResidualTest, ::testing::Values(0.0, 10.0));

TEST(LineResidual, DistancesAndBoundedAngleTerm) {
  const StereoRig rig = EurocLikeRig();
  const Rigid3d cam_from_world;  // identity
  // A vertical line (a roof bolt): its projection is the column u = cx + fx * 0.5 / 4.
  const PluckerLine line =
      PluckerLine::FromPoints(Eigen::Vector3d(0.5, -1.0, 4.0), Eigen::Vector3d(0.5, 1.0, 4.0));
  const double u0 = rig.camera.cx + rig.camera.fx * 0.5 / 4.0;
  Eigen::Vector3d e;
  ASSERT_TRUE(LineResidual(rig.camera, cam_from_world, line, Eigen::Vector2d(u0 + 2.0, 100.0),
                           Eigen::Vector2d(u0 + 5.0, 300.0), 10.0, &e));
  // Signed distances of the endpoints are 2 and 5 px (same sign), e3 = w * sin(angle).
  EXPECT_NEAR(std::abs(e(0)), 2.0, 1e-9);
  EXPECT_NEAR(std::abs(e(1)), 5.0, 1e-9);
  EXPECT_GT(e(0) * e(1), 0.0);
  const double sine = 3.0 / std::hypot(3.0, 200.0);
  EXPECT_NEAR(std::abs(e(2)), 10.0 * sine, 1e-9);
  // Slopes are infinite here; the residual stays finite.
  EXPECT_TRUE(e.allFinite());
}

}  // namespace
}  // namespace slslam
