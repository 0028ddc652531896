#include "slslam/core/rigid3.h"

#include <gtest/gtest.h>
#include <Eigen/Geometry>

namespace slslam {
namespace {

Rigid3d Pose(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  return Rigid3d(Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix(), t);
}

TEST(Rigid3d, DefaultIsTheIdentity) {
  const Rigid3d identity;
  EXPECT_EQ(identity.rotation, Eigen::Matrix3d::Identity());
  EXPECT_EQ(identity.translation, Eigen::Vector3d::Zero());
  const Eigen::Vector3d x(1.5, -2.0, 3.25);
  EXPECT_EQ(identity * x, x);
}

TEST(Rigid3d, ApplyIsRotationTimesPointPlusTranslationExactly) {
  const Rigid3d b_from_a = Pose(0.7, Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(0.1, -0.4, 2.0));
  const Eigen::Vector3d x_a(0.3, 1.7, -5.2);
  const Eigen::Vector3d expected = b_from_a.rotation * x_a + b_from_a.translation;
  const Eigen::Vector3d x_b = b_from_a * x_a;
  for (int i = 0; i < 3; ++i) EXPECT_EQ(x_b[i], expected[i]);  // bit for bit
  // A rotation about z by 90 degrees then a shift: (1, 0, 0) -> (0, 1, 0) + t.
  const Rigid3d quarter = Pose(M_PI / 2, Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE((quarter * Eigen::Vector3d(1, 0, 0)).isApprox(Eigen::Vector3d(1, 3, 3), 1e-12));
}

TEST(Rigid3d, CompositionChainsTheFrames) {
  const Rigid3d b_from_a = Pose(0.3, Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(1, 0, 0));
  const Rigid3d c_from_b = Pose(-1.1, Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(0, 2, -1));
  const Rigid3d c_from_a = c_from_b * b_from_a;
  const Eigen::Vector3d x_a(0.5, -0.25, 4.0);
  EXPECT_TRUE((c_from_a * x_a).isApprox(c_from_b * (b_from_a * x_a), 1e-12));
  EXPECT_EQ(c_from_a.rotation, c_from_b.rotation * b_from_a.rotation);
  EXPECT_EQ(c_from_a.translation, c_from_b.rotation * b_from_a.translation + c_from_b.translation);
  // Associative up to rounding.
  const Rigid3d d_from_c = Pose(2.0, Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(-3, 1, 0.5));
  EXPECT_TRUE(((d_from_c * c_from_b) * b_from_a)
                  .ToMatrix4()
                  .isApprox((d_from_c * (c_from_b * b_from_a)).ToMatrix4(), 1e-12));
}

TEST(Rigid3d, InverseUndoesTheTransform) {
  const Rigid3d cam_from_world =
      Pose(0.9, Eigen::Vector3d(1, -2, 0.5), Eigen::Vector3d(0.2, 0.3, -1.5));
  const Rigid3d world_from_cam = cam_from_world.Inverse();
  const Eigen::Vector3d x_w(2.0, -1.0, 7.0);
  EXPECT_TRUE((world_from_cam * (cam_from_world * x_w)).isApprox(x_w, 1e-12));
  EXPECT_TRUE((cam_from_world * world_from_cam).ToMatrix4().isIdentity(1e-12));
  EXPECT_TRUE((world_from_cam * cam_from_world).ToMatrix4().isIdentity(1e-12));
  // The camera centre is the translation of the inverse (up to rounding) and maps to the camera
  // origin.
  EXPECT_TRUE(cam_from_world.Center().isApprox(world_from_cam.translation, 1e-12));
  EXPECT_TRUE((cam_from_world * cam_from_world.Center()).isZero(1e-12));
  EXPECT_EQ(cam_from_world.Center(),
            Eigen::Vector3d(-cam_from_world.rotation.transpose() * cam_from_world.translation));
}

TEST(Rigid3d, Matrix4RoundTrip) {
  const Rigid3d b_from_a = Pose(1.3, Eigen::Vector3d(3, -1, 2), Eigen::Vector3d(4, 5, 6));
  const Eigen::Matrix4d m = b_from_a.ToMatrix4();
  EXPECT_EQ(m.row(3), Eigen::RowVector4d(0, 0, 0, 1));
  EXPECT_EQ(Eigen::Matrix3d(m.topLeftCorner<3, 3>()), b_from_a.rotation);
  EXPECT_EQ(Eigen::Vector3d(m.topRightCorner<3, 1>()), b_from_a.translation);
  const Rigid3d back = Rigid3d::FromMatrix4(m);
  EXPECT_EQ(back.rotation, b_from_a.rotation);
  EXPECT_EQ(back.translation, b_from_a.translation);
  // The matrix acts on homogeneous points as the transform does.
  const Eigen::Vector3d x(0.1, 0.2, 0.3);
  EXPECT_TRUE((m * x.homogeneous()).head<3>().isApprox(b_from_a * x, 1e-12));
  // And composes as the matrices do.
  const Rigid3d c_from_b = Pose(-0.4, Eigen::Vector3d(0, 1, 1), Eigen::Vector3d(-1, 0, 2));
  EXPECT_TRUE((c_from_b * b_from_a).ToMatrix4().isApprox(c_from_b.ToMatrix4() * m, 1e-12));
  EXPECT_TRUE(b_from_a.Inverse().ToMatrix4().isApprox(m.inverse(), 1e-12));
}

}  // namespace
}  // namespace slslam
