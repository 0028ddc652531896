#include "slslam/core/stereo_rectifier.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace slslam {
namespace {

RadTanCamera MakeCamera(double fx, double cx, std::array<double, 4> distortion) {
  return RadTanCamera{PinholeCamera{fx, fx * 0.998, cx, 240.0, 640, 480}, distortion};
}

Eigen::Matrix4d SmallRotationBaseline(double baseline_m) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = (Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(-0.005, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  T.topRightCorner<3, 1>() = Eigen::Vector3d(baseline_m, 0.002, -0.001);
  return T;
}

// Projects a 3-D point (left camera frame) through a distorted camera, as the sensor would see it.
cv::Point2d ProjectDistorted(const RadTanCamera& camera, const Eigen::Matrix4d& T_cam_left,
                             const Eigen::Vector3d& point_in_left) {
  cv::Mat K, D = (cv::Mat_<double>(1, 4) << camera.distortion[0], camera.distortion[1],
                  camera.distortion[2], camera.distortion[3]);
  cv::eigen2cv(camera.pinhole.K(), K);
  cv::Mat R, rvec, tvec;
  cv::eigen2cv(Eigen::Matrix3d(T_cam_left.topLeftCorner<3, 3>()), R);
  cv::Rodrigues(R, rvec);
  cv::eigen2cv(Eigen::Vector3d(T_cam_left.topRightCorner<3, 1>()), tvec);
  std::vector<cv::Point3d> object{{point_in_left.x(), point_in_left.y(), point_in_left.z()}};
  std::vector<cv::Point2d> image;
  cv::projectPoints(object, rvec, tvec, K, D, image);
  return image[0];
}

// Undistort-rectify a raw pixel with the same model the maps use.
cv::Point2d RectifyPixel(const RadTanCamera& camera, const Eigen::Matrix3d& R_rect_cam,
                         const PinholeCamera& rect, const cv::Point2d& raw) {
  cv::Mat K, R, P = (cv::Mat_<double>(3, 3) << rect.fx, 0, rect.cx, 0, rect.fy, rect.cy, 0, 0, 1);
  cv::Mat D = (cv::Mat_<double>(1, 4) << camera.distortion[0], camera.distortion[1],
               camera.distortion[2], camera.distortion[3]);
  cv::eigen2cv(camera.pinhole.K(), K);
  cv::eigen2cv(R_rect_cam, R);
  std::vector<cv::Point2d> in{raw}, out;
  cv::undistortPoints(in, out, K, D, R, P);
  return out[0];
}

TEST(StereoRectifier, RectifiedPointsShareRowsAndGiveMetricDepth) {
  const RadTanCamera left = MakeCamera(460.0, 320.0, {-0.28, 0.07, 2e-4, 2e-5});
  const RadTanCamera right = MakeCamera(457.0, 318.0, {-0.27, 0.068, -1e-4, 3e-5});
  const Eigen::Matrix4d T_left_right = SmallRotationBaseline(0.11);
  const StereoRectifier rectifier(left, right, T_left_right);

  const double true_baseline = T_left_right.topRightCorner<3, 1>().norm();
  EXPECT_NEAR(rectifier.baseline_m(), true_baseline, 1e-9);
  const PinholeCamera& rect = rectifier.rectified_camera();
  const Eigen::Matrix4d T_right_left = T_left_right.inverse();
  for (const Eigen::Vector3d p : {Eigen::Vector3d(0.4, 0.3, 3.0), Eigen::Vector3d(-0.5, -0.2, 5.0),
                                  Eigen::Vector3d(0.1, 0.0, 1.5)}) {
    const cv::Point2d raw_l = ProjectDistorted(left, Eigen::Matrix4d::Identity(), p);
    const cv::Point2d raw_r = ProjectDistorted(right, T_right_left, p);
    const cv::Point2d rect_l = RectifyPixel(left, rectifier.R_rect_left(), rect, raw_l);
    const cv::Point2d rect_r = RectifyPixel(right, rectifier.R_rectright_right(), rect, raw_r);
    EXPECT_NEAR(rect_l.y, rect_r.y, 1e-3) << "rows differ for point " << p.transpose();
    const double disparity = rect_l.x - rect_r.x;
    const double depth_in_rect = (rectifier.R_rect_left() * p).z();
    EXPECT_NEAR(rect.fx * rectifier.baseline_m() / disparity, depth_in_rect, 1e-3 * depth_in_rect);
  }
}

TEST(StereoRectifier, RejectsWrongImageSize) {
  const RadTanCamera cam = MakeCamera(460.0, 320.0, {0, 0, 0, 0});
  const StereoRectifier rectifier(cam, cam, SmallRotationBaseline(0.1));
  const cv::Mat good(480, 640, CV_8UC1, cv::Scalar(10)), bad(240, 320, CV_8UC1, cv::Scalar(10));
  EXPECT_NO_THROW(rectifier.Rectify(good, good));
  EXPECT_THROW(rectifier.Rectify(good, bad), std::invalid_argument);
  EXPECT_THROW(rectifier.Rectify(cv::Mat(), good), std::invalid_argument);
  EXPECT_THROW(rectifier.Rectify(cv::Mat(480, 640, CV_8UC3), good), std::invalid_argument);
}

TEST(StereoRectifier, RejectsSwappedCamerasAndNonRigidExtrinsics) {
  const RadTanCamera cam = MakeCamera(460.0, 320.0, {0, 0, 0, 0});
  EXPECT_THROW(StereoRectifier(cam, cam, SmallRotationBaseline(-0.1)), std::invalid_argument);
  Eigen::Matrix4d scaled = SmallRotationBaseline(0.1);
  scaled.topLeftCorner<3, 3>() *= 1.1;
  EXPECT_THROW(StereoRectifier(cam, cam, scaled), std::invalid_argument);
  Eigen::Matrix4d nan = SmallRotationBaseline(0.1);
  nan(0, 3) = std::nan("");
  EXPECT_THROW(StereoRectifier(cam, cam, nan), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
