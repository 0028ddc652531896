#include "slslam/tracking/stereo_flow.h"

#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "../test_support.h"

namespace slslam {
namespace {

// The image of a camera X_cam = R X + t looking at the plane Z = depth_m of the reference
// camera, whose own image is `plane`: the homography K (R + t n^T / d) K^-1.
cv::Mat View(const cv::Mat& plane, const StereoRig& rig, const Rigid3d& cam_from_reference,
             double depth_m) {
  const Eigen::Matrix3d K = rig.camera.K();
  const Eigen::Matrix3d H =
      K *
      (cam_from_reference.rotation +
       cam_from_reference.translation * Eigen::Vector3d::UnitZ().transpose() / depth_m) *
      K.inverse();
  cv::Mat H_cv, out;
  cv::eigen2cv(H, H_cv);
  cv::warpPerspective(plane, out, H_cv, plane.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  cv::Mat noise(out.size(), CV_32F);
  cv::randn(noise, 0.0, 1.0);
  out += noise;
  cv::Mat grey;
  out.convertTo(grey, CV_8U);
  return grey;
}

// A faint, smooth relief (a lining's shading: blobs of about 10 px, 10 grey levels) on a wall 2 m
// ahead; the camera moves 4 cm forward, 5 mm sideways and turns 1 degree: the flow recovers the
// motion to a few millimetres and a fraction of a milliradian, also when the lamp flickers.
TEST(StereoFlow, RecoversTheMotionOverAFaintSmoothTexture) {
  const StereoRig rig = test::EurocLikeRig();
  cv::Mat coarse(480 / 4, 752 / 4, CV_32F);
  cv::theRNG().state = 11;
  cv::randn(coarse, 0.0, 1.0);
  cv::Mat plane;
  cv::resize(coarse, plane, cv::Size(752, 480), 0, 0, cv::INTER_CUBIC);
  cv::GaussianBlur(plane, plane, cv::Size(), 3.0);
  cv::Scalar mean, stddev;
  cv::meanStdDev(plane, mean, stddev);
  plane = (plane - mean[0]) * (10.0 / stddev[0]) + 80.0;
  const double depth_m = 2.0;
  const Rigid3d right_from_left(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.11, 0.0, 0.0));
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(1.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d centre(0.005, 0.0, 0.04);  // the current camera in the previous one
  const Rigid3d cur_from_prev(R, -R * centre);
  const cv::Mat left_prev = View(plane, rig, Rigid3d(), depth_m);
  const cv::Mat right_prev = View(plane, rig, right_from_left, depth_m);
  const cv::Mat left_cur = View(plane, rig, cur_from_prev, depth_m);

  const auto motion = MeasureStereoFlow(left_prev, right_prev, left_cur, rig, 30);
  ASSERT_TRUE(motion.has_value());
  EXPECT_GE(motion->inliers, 30);
  const Eigen::Vector3d error = motion->cur_from_prev.translation - cur_from_prev.translation;
  EXPECT_LT(error.norm(), 3e-3) << motion->cur_from_prev.translation.transpose();
  const double angle = Eigen::AngleAxisd(motion->cur_from_prev.rotation * R.transpose()).angle();
  EXPECT_LT(angle, 1e-3);
  // Its covariance: positive, and the error within a few of its sigmas.
  const Eigen::Matrix3d translation_covariance = motion->covariance.bottomRightCorner<3, 3>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(translation_covariance);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  EXPECT_LT(error.dot(translation_covariance.inverse() * error), 30.0);

  // The lamp flickering to 60 % in the current frame: the same motion (each image is scaled to
  // one mean first).
  cv::Mat dimmer;
  left_cur.convertTo(dimmer, CV_8U, 0.6);
  const auto flickered = MeasureStereoFlow(left_prev, right_prev, dimmer, rig, 30);
  ASSERT_TRUE(flickered.has_value());
  EXPECT_LT((flickered->cur_from_prev.translation - cur_from_prev.translation).norm(), 3e-3);

  // A lining without relief: nothing to track, no measurement; nor from images of another size.
  const cv::Mat flat(480, 752, CV_8U, cv::Scalar(80));
  EXPECT_FALSE(MeasureStereoFlow(flat, flat, flat, rig, 30).has_value());
  cv::Mat small;
  cv::resize(left_cur, small, cv::Size(376, 240));
  EXPECT_FALSE(MeasureStereoFlow(left_prev, right_prev, small, rig, 30).has_value());
}

}  // namespace
}  // namespace slslam
