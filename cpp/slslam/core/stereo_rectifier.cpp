#include "slslam/core/stereo_rectifier.h"

#include <cmath>

#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "slslam/core/check.h"

namespace slslam {
namespace {

// A rotation block is accepted as orthonormal within this tolerance; calibration files carry
// about 10 significant digits, so 1e-6 rejects typos but not rounding.
constexpr double kRotationTolerance = 1e-6;

void CheckRigid(const Eigen::Matrix4d& T) {
  Require(T.allFinite(), "stereo extrinsics T_left_right contain NaN or Inf");
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  const double orthonormality_error = (R * R.transpose() - Eigen::Matrix3d::Identity()).norm();
  SLSLAM_CHECK(orthonormality_error < kRotationTolerance && R.determinant() > 0.0,
               "stereo extrinsics T_left_right: rotation block is not a rotation (|R R^T - I| = ",
               orthonormality_error, ")");
  Require(T.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)),
          "stereo extrinsics T_left_right: last row must be [0 0 0 1]");
}

cv::Mat IntrinsicMatrix(const PinholeCamera& camera) {
  cv::Mat k;
  cv::eigen2cv(camera.K(), k);
  return k;
}

cv::Mat DistortionVector(const RadTanCamera& camera) {
  return (cv::Mat_<double>(1, 4) << camera.distortion[0], camera.distortion[1],
          camera.distortion[2], camera.distortion[3]);
}

}  // namespace

StereoRectifier::StereoRectifier(const RadTanCamera& left, const RadTanCamera& right,
                                 const Eigen::Matrix4d& T_left_right) {
  left.Check();
  right.Check();
  CheckRigid(T_left_right);
  SLSLAM_CHECK(
      left.pinhole.width == right.pinhole.width && left.pinhole.height == right.pinhole.height,
      "left and right image sizes differ: ", left.pinhole.width, "x", left.pinhole.height, " vs ",
      right.pinhole.width, "x", right.pinhole.height);

  // OpenCV wants the transform that maps left-camera coordinates into the right camera.
  const Eigen::Matrix4d T_right_left = T_left_right.inverse();
  cv::Mat R, t;
  cv::eigen2cv(Eigen::Matrix3d(T_right_left.topLeftCorner<3, 3>()), R);
  cv::eigen2cv(Eigen::Vector3d(T_right_left.topRightCorner<3, 1>()), t);

  const cv::Size size(left.pinhole.width, left.pinhole.height);
  const cv::Mat K_left = IntrinsicMatrix(left.pinhole), K_right = IntrinsicMatrix(right.pinhole);
  const cv::Mat D_left = DistortionVector(left), D_right = DistortionVector(right);
  cv::Mat R1, R2, P1, P2, Q;
  // alpha = 0: crop to valid pixels only, so no black borders produce spurious corners and lines.
  cv::stereoRectify(K_left, D_left, K_right, D_right, size, R, t, R1, R2, P1, P2, Q,
                    cv::CALIB_ZERO_DISPARITY, /*alpha=*/0.0, size);

  rectified_.fx = P1.at<double>(0, 0);
  rectified_.fy = P1.at<double>(1, 1);
  rectified_.cx = P1.at<double>(0, 2);
  rectified_.cy = P1.at<double>(1, 2);
  rectified_.width = size.width;
  rectified_.height = size.height;
  rectified_.Check();
  // P2(0,3) = -fx * baseline for a right camera on the +x side of the left one.
  baseline_m_ = -P2.at<double>(0, 3) / P2.at<double>(0, 0);
  SLSLAM_CHECK(std::isfinite(baseline_m_) && baseline_m_ > 0.0,
               "the right camera is not to the right of the left camera (rectified baseline ",
               baseline_m_, " m); check the order of cam0/cam1 and T_left_right");
  cv::cv2eigen(R1, R_rect_left_);
  cv::cv2eigen(R2, R_rectright_right_);

  // Fixed-point maps (CV_16SC2) make remap about twice as fast as float maps.
  cv::initUndistortRectifyMap(K_left, D_left, R1, P1, size, CV_16SC2, left_map1_, left_map2_);
  cv::initUndistortRectifyMap(K_right, D_right, R2, P2, size, CV_16SC2, right_map1_, right_map2_);
}

cv::Mat StereoRectifier::RectifyOne(const cv::Mat& image, bool is_left) const {
  const char* which = is_left ? "left" : "right";
  SLSLAM_CHECK(!image.empty(), "the ", which, " image is empty");
  SLSLAM_CHECK(image.type() == CV_8UC1, "the ", which,
               " image must be 8-bit single channel (got OpenCV type ", image.type(), ")");
  SLSLAM_CHECK(image.cols == rectified_.width && image.rows == rectified_.height, "the ", which,
               " image is ", image.cols, "x", image.rows, " but the calibration is for ",
               rectified_.width, "x", rectified_.height);
  cv::Mat out;
  cv::remap(image, out, is_left ? left_map1_ : right_map1_, is_left ? left_map2_ : right_map2_,
            cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
  return out;
}

std::pair<cv::Mat, cv::Mat> StereoRectifier::Rectify(const cv::Mat& left,
                                                     const cv::Mat& right) const {
  return {RectifyOne(left, true), RectifyOne(right, false)};
}

}  // namespace slslam
