#include "slslam/geometry/plucker_line.h"

#include <random>

#include <gtest/gtest.h>

#include "slslam/geometry/rotation.h"

namespace slslam {
namespace {

PinholeCamera TestCamera() {
  PinholeCamera camera;
  camera.fx = 458.0;
  camera.fy = 457.0;
  camera.cx = 367.0;
  camera.cy = 248.0;
  camera.width = 752;
  camera.height = 480;
  return camera;
}

// Same line up to a non-zero scale (sign included).
void ExpectSameLine(const PluckerLine& a, const PluckerLine& b, double tol = 1e-9) {
  const PluckerLine na = a.Normalized();
  const PluckerLine nb = b.Normalized();
  const double sign = na.v.dot(nb.v) >= 0.0 ? 1.0 : -1.0;
  EXPECT_LT((na.v - sign * nb.v).norm(), tol);
  EXPECT_LT((na.n - sign * nb.n).norm(), tol);
}

TEST(PluckerLine, FromPointsSatisfiesDefinition) {
  const Eigen::Vector3d a(1.0, 2.0, 5.0);
  const Eigen::Vector3d b(-1.0, 0.5, 7.0);
  const PluckerLine line = PluckerLine::FromPoints(a, b);
  EXPECT_NEAR(line.n.dot(line.v), 0.0, 1e-12);
  // Any point of the line gives the same moment.
  const Eigen::Vector3d p = a + 0.3 * (b - a);
  EXPECT_LT((p.cross(line.v) - line.n).norm(), 1e-12);
  // The closest point to the origin lies on the line and is perpendicular to it.
  const Eigen::Vector3d c = line.ClosestPointToOrigin();
  EXPECT_NEAR(c.dot(line.v), 0.0, 1e-12);
  EXPECT_LT((c.cross(line.v) - line.n).norm(), 1e-12);
  EXPECT_THROW(PluckerLine::FromPoints(a, a), std::invalid_argument);
}

TEST(PluckerLine, TwoViewPlanesRecoverTheLine) {
  // Two cameras 0.5 m apart observe the segment a-b; the planes through each camera centre and
  // the projected segment intersect in the 3-D line (the SL-SLAM paper's line initialisation).
  const PinholeCamera camera = TestCamera();
  const Eigen::Vector3d a(-0.8, 0.4, 6.0);
  const Eigen::Vector3d b(0.9, -0.3, 7.5);
  const Eigen::Matrix3d R1 = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d t1 = Eigen::Vector3d::Zero();
  const Eigen::Matrix3d R2 = ExpSO3(Eigen::Vector3d(0.02, -0.05, 0.01));
  const Eigen::Vector3d t2(-0.5, 0.05, 0.1);
  auto project = [&](const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const Eigen::Vector3d& p) {
    return camera.Project(R * p + t);
  };
  const Eigen::Vector4d plane1 =
      BackProjectedPlane(camera, Rigid3d(R1, t1), project(R1, t1, a), project(R1, t1, b));
  const Eigen::Vector4d plane2 =
      BackProjectedPlane(camera, Rigid3d(R2, t2), project(R2, t2, a), project(R2, t2, b));
  ExpectSameLine(PluckerLine::FromPlanes(plane1, plane2), PluckerLine::FromPoints(a, b), 1e-7);
  EXPECT_THROW(PluckerLine::FromPlanes(plane1, plane1), std::invalid_argument);
}

TEST(PluckerLine, TransformMatchesTransformedPoints) {
  const Eigen::Vector3d a(1.0, -2.0, 3.0);
  const Eigen::Vector3d b(0.5, 1.0, 4.0);
  const Eigen::Matrix3d R = ExpSO3(Eigen::Vector3d(0.3, -0.2, 0.7));
  const Eigen::Vector3d t(0.4, -1.0, 2.0);
  ExpectSameLine(PluckerLine::FromPoints(a, b).Transformed(Rigid3d(R, t)),
                 PluckerLine::FromPoints(R * a + t, R * b + t));
}

TEST(PluckerLine, ProjectionGoesThroughProjectedPoints) {
  const PinholeCamera camera = TestCamera();
  const Eigen::Vector3d a(-0.8, 0.4, 6.0);
  const Eigen::Vector3d b(0.9, -0.3, 7.5);
  const Eigen::Vector3d l = LineProjectionMatrix(camera) * PluckerLine::FromPoints(a, b).n;
  for (const Eigen::Vector3d& p : {a, b, Eigen::Vector3d(0.5 * (a + b))}) {
    const Eigen::Vector2d uv = camera.Project(p);
    EXPECT_NEAR((l.x() * uv.x() + l.y() * uv.y() + l.z()) / l.head<2>().norm(), 0.0, 1e-9);
  }
}

TEST(PluckerLine, ClosestPointToRayCutsTheLineAtTheObservedEndpoint) {
  const PinholeCamera camera = TestCamera();
  const Eigen::Vector3d a(-0.8, 0.4, 6.0);
  const Eigen::Vector3d b(0.9, -0.3, 7.5);
  const PluckerLine line = PluckerLine::FromPoints(a, b);
  EXPECT_LT((line.ClosestPointToRay(camera.Unproject(camera.Project(a))) - a).norm(), 1e-9);
  EXPECT_LT((line.ClosestPointToRay(camera.Unproject(camera.Project(b))) - b).norm(), 1e-9);
}

TEST(OrthonormalLine, RoundTripAndFourDofUpdate) {
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss(0.0, 2.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d a(gauss(rng), gauss(rng), gauss(rng));
    const Eigen::Vector3d b(gauss(rng), gauss(rng), gauss(rng));
    const PluckerLine line = PluckerLine::FromPoints(a, b);
    const OrthonormalLine ortho = OrthonormalLine::FromPlucker(line);
    EXPECT_GT(ortho.phi, 0.0);
    EXPECT_LT(ortho.phi, M_PI / 2);
    ExpectSameLine(ortho.ToPlucker(), line, 1e-9);
    // Any increment keeps a valid Pluecker line (n . v = 0).
    const PluckerLine moved = ortho.Plus(Eigen::Vector4d(0.1, -0.2, 0.05, 0.1)).ToPlucker();
    EXPECT_NEAR(moved.n.dot(moved.v), 0.0, 1e-12);
  }
  PluckerLine through_origin;
  through_origin.n.setZero();
  through_origin.v = Eigen::Vector3d(0.0, 0.0, 2.0);
  ExpectSameLine(OrthonormalLine::FromPlucker(through_origin).ToPlucker(), through_origin);
  PluckerLine bad;
  bad.v.setZero();
  EXPECT_THROW(OrthonormalLine::FromPlucker(bad), std::invalid_argument);
}

TEST(OrthonormalLine, PluckerJacobianMatchesNumericDifferentiation) {
  const OrthonormalLine ortho = OrthonormalLine::FromPlucker(
      PluckerLine::FromPoints(Eigen::Vector3d(1.0, 2.0, 3.0), Eigen::Vector3d(-2.0, 0.5, 6.0)));
  const Eigen::Matrix<double, 6, 4> analytic = ortho.PluckerJacobian();
  const double h = 1e-6;
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector4d delta = Eigen::Vector4d::Zero();
    delta(k) = h;
    const PluckerLine plus = ortho.Plus(delta).ToPlucker();
    const PluckerLine minus = ortho.Plus(-delta).ToPlucker();
    Eigen::Matrix<double, 6, 1> numeric;
    numeric << (plus.n - minus.n) / (2 * h), (plus.v - minus.v) / (2 * h);
    EXPECT_LT((numeric - analytic.col(k)).norm(), 1e-8) << "column " << k;
  }
}

}  // namespace
}  // namespace slslam
