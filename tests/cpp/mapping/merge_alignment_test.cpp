// A merge's alignment about gravity only (YawAndPositionAlignment): gravity's direction in the
// source world lands on the target's, the merging keyframe's centre where the verified alignment
// put it, and an alignment that already satisfied both is left as it was.
#include <gtest/gtest.h>

#include "slslam/geometry/rotation.h"
#include "slslam/mapping/loop_closer.h"

namespace slslam {
namespace {

TEST(YawAndPositionAlignment, MapsGravityOntoGravityAndKeepsThePivot) {
  const Eigen::Vector3d g_target = Eigen::Vector3d(0.1, 9.7, -0.5).normalized() * 9.81;
  // A source world turned 40 degrees about gravity and shifted: the true alignment.
  const Eigen::Matrix3d R_true = ExpSO3(g_target.normalized() * (40.0 * M_PI / 180.0)) *
                                 ExpSO3(Eigen::Vector3d(0.2, -0.1, 0.3));
  const Eigen::Vector3d g_source = R_true.transpose() * g_target;
  const Rigid3d truth(R_true, Eigen::Vector3d(3.0, -1.0, 0.5));
  // The verified alignment tilted by 2 degrees (the camera's error in roll and pitch).
  const Rigid3d verified(ExpSO3(Eigen::Vector3d(0.02, 0.0, 0.025)) * R_true, truth.translation);
  const Eigen::Vector3d pivot(1.0, 2.0, -4.0);
  const Rigid3d aligned = YawAndPositionAlignment(verified, g_source, g_target, pivot);
  EXPECT_LT((aligned.rotation * g_source - g_target).norm(), 1e-9);
  EXPECT_LT((aligned * pivot - verified * pivot).norm(), 1e-9);
  // What is left of the tilt: the part about gravity (the verified tilt's component along it).
  const double left = LogSO3(Eigen::Quaterniond(aligned.rotation * R_true.transpose())).norm();
  EXPECT_LT(left, 0.5 * M_PI / 180.0);
  EXPECT_GT(LogSO3(Eigen::Quaterniond(verified.rotation * R_true.transpose())).norm(),
            1.5 * M_PI / 180.0);
  // An alignment that already maps gravity onto gravity is kept.
  const Rigid3d kept = YawAndPositionAlignment(truth, g_source, g_target, pivot);
  EXPECT_LT((kept.rotation - truth.rotation).norm(), 1e-12);
  EXPECT_LT((kept.translation - truth.translation).norm(), 1e-9);
}

}  // namespace
}  // namespace slslam
