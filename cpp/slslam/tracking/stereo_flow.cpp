#include "slslam/tracking/stereo_flow.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace slslam {
namespace {

constexpr int kMaxCorners = 300;         // corners tracked per frame [-]
constexpr double kCornerQuality = 1e-3;  // of the strongest corner's response [-]
// Corners are detected on the image at half size (a quarter of the cost): smooth relief has its
// corners at that scale anyway, and Lucas-Kanade places them on the full image.
constexpr double kCornerSpacingPx = 4.0;     // at half size [px]
constexpr int kCornerBlockPx = 15;           // at half size [px]
constexpr int kFlowWindowPx = 21;            // Lucas-Kanade window [px]
constexpr int kFlowLevels = 3;               // pyramid levels above the image [-]
constexpr float kMaxBackwardErrorPx = 0.5f;  // forward then backward track must return [px]
constexpr float kMaxRowOffsetPx = 1.0f;      // rectified stereo: same row [px]
// Depths beyond this many baselines are not used: their stereo depth's error moves the motion
// more than their flow constrains it (the lit end of a flat lining 10-20 m ahead: the forward
// motion came out 10 % short with them, 2 % without) [-]
constexpr double kMaxDepthBaselines = 60.0;
constexpr double kDisparitySigmaPx = 0.2;  // a Lucas-Kanade disparity's error [px]
constexpr float kRansacReprojectionPx = 1.0f;
constexpr int kRansacIterations = 100;
constexpr double kMinReprojectionSigmaPx = 0.3;  // the covariance's floor on the residual [px]
constexpr double kMeanGrey = 80.0;  // each image scaled to this mean: a flicker is a gain [-]

cv::Mat Normalised(const cv::Mat& grey) {
  const double mean = cv::mean(grey)[0];
  cv::Mat out;
  grey.convertTo(out, CV_8U, mean > 1.0 ? kMeanGrey / mean : 1.0);
  return out;
}

const cv::Size kWindow(kFlowWindowPx, kFlowWindowPx);
// (10 iterations: on smooth shading the rest rarely converge further)
const cv::TermCriteria kStop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 10, 0.01);

std::vector<cv::Mat> Pyramid(const cv::Mat& image) {
  std::vector<cv::Mat> pyramid;
  cv::buildOpticalFlowPyramid(image, pyramid, kWindow, kFlowLevels);
  return pyramid;
}

}  // namespace

std::optional<StereoFlowMotion> MeasureStereoFlow(const cv::Mat& left_prev,
                                                  const cv::Mat& right_prev,
                                                  const cv::Mat& left_cur, const StereoRig& rig,
                                                  int min_inliers) {
  const auto usable = [&](const cv::Mat& m) {
    return !m.empty() && m.type() == CV_8UC1 && m.size() == left_prev.size();
  };
  if (!usable(left_prev) || !usable(right_prev) || !usable(left_cur)) return std::nullopt;
  const std::vector<cv::Mat> lp = Pyramid(Normalised(left_prev));
  const std::vector<cv::Mat> rp = Pyramid(Normalised(right_prev));
  const std::vector<cv::Mat> lc = Pyramid(Normalised(left_cur));
  cv::Mat half;
  cv::pyrDown(lp[0], half);
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(half, corners, kMaxCorners, kCornerQuality, kCornerSpacingPx,
                          cv::noArray(), kCornerBlockPx);
  if (static_cast<int>(corners.size()) < std::max(min_inliers, 6)) return std::nullopt;
  // (a half-size pixel's centre at (2 u + 0.5, 2 v + 0.5) of the full image)
  for (cv::Point2f& c : corners) c = c * 2.0f + cv::Point2f(0.5f, 0.5f);
  // Into the right image (the same rectified row, a depth within range); those into the current
  // image and back.
  const PinholeCamera& cam = rig.camera;
  std::vector<cv::Point2f> in_right;
  std::vector<unsigned char> ok;
  std::vector<float> error;
  cv::calcOpticalFlowPyrLK(lp, rp, corners, in_right, ok, error, kWindow, kFlowLevels, kStop);
  std::vector<cv::Point2f> stereo;
  std::vector<float> disparities;
  for (size_t i = 0; i < corners.size(); ++i) {
    const float disparity = corners[i].x - in_right[i].x;
    if (ok[i] && disparity >= cam.fx / kMaxDepthBaselines &&
        std::abs(corners[i].y - in_right[i].y) <= kMaxRowOffsetPx) {
      stereo.push_back(corners[i]);
      disparities.push_back(disparity);
    }
  }
  if (static_cast<int>(stereo.size()) < std::max(min_inliers, 6)) return std::nullopt;
  std::vector<cv::Point2f> in_cur, back;
  std::vector<unsigned char> back_ok;
  cv::calcOpticalFlowPyrLK(lp, lc, stereo, in_cur, ok, error, kWindow, kFlowLevels, kStop);
  cv::calcOpticalFlowPyrLK(lc, lp, in_cur, back, back_ok, error, kWindow, kFlowLevels, kStop);
  std::vector<cv::Point3f> points;
  std::vector<cv::Point2f> observed;
  for (size_t i = 0; i < stereo.size(); ++i) {
    const cv::Point2f d = back[i] - stereo[i];
    if (!ok[i] || !back_ok[i] || !(d.dot(d) < kMaxBackwardErrorPx * kMaxBackwardErrorPx)) continue;
    const double z = cam.fx * rig.baseline_m / disparities[i];
    points.emplace_back(static_cast<float>((stereo[i].x - cam.cx) * z / cam.fx),
                        static_cast<float>((stereo[i].y - cam.cy) * z / cam.fy),
                        static_cast<float>(z));
    observed.push_back(in_cur[i]);
  }
  if (static_cast<int>(points.size()) < std::max(min_inliers, 6)) return std::nullopt;
  cv::Mat K;
  cv::eigen2cv(cam.K(), K);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  if (!cv::solvePnPRansac(points, observed, K, cv::noArray(), rvec, tvec, false, kRansacIterations,
                          kRansacReprojectionPx, 0.99, inliers, cv::SOLVEPNP_ITERATIVE) ||
      static_cast<int>(inliers.size()) < std::max(min_inliers, 6)) {
    return std::nullopt;
  }
  cv::Mat R_cv;
  cv::Rodrigues(rvec, R_cv);
  StereoFlowMotion out;
  cv::cv2eigen(R_cv, out.cur_from_prev.rotation);
  cv::cv2eigen(tvec, out.cur_from_prev.translation);
  if (!out.cur_from_prev.rotation.allFinite() || !out.cur_from_prev.translation.allFinite()) {
    return std::nullopt;
  }
  // Gauss-Newton information of the pose on the inliers (x_cur = Exp(dtheta) R x + t + dt),
  // each point weighted by its reprojection's variance: the residuals' (at least
  // kMinReprojectionSigmaPx) and its stereo depth's error moved into the current image.
  double squared_sum = 0.0;
  for (const int i : inliers) {
    const Eigen::Vector3d p(points[i].x, points[i].y, points[i].z);
    const Eigen::Vector3d x = out.cur_from_prev.rotation * p + out.cur_from_prev.translation;
    if (!(x.z() > 1e-6)) return std::nullopt;
    const Eigen::Vector2d r(cam.fx * x.x() / x.z() + cam.cx - observed[i].x,
                            cam.fy * x.y() / x.z() + cam.cy - observed[i].y);
    squared_sum += r.squaredNorm();
  }
  const double pixel_sq = std::max(kMinReprojectionSigmaPx * kMinReprojectionSigmaPx,
                                   squared_sum / (2.0 * static_cast<double>(inliers.size())));
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  for (const int i : inliers) {
    const Eigen::Vector3d p(points[i].x, points[i].y, points[i].z);
    const Eigen::Vector3d rotated = out.cur_from_prev.rotation * p;
    const Eigen::Vector3d x = rotated + out.cur_from_prev.translation;
    if (!(x.z() > 1e-6)) return std::nullopt;
    const double iz = 1.0 / x.z();
    Eigen::Matrix<double, 2, 3> d_proj;
    d_proj << cam.fx * iz, 0.0, -cam.fx * x.x() * iz * iz, 0.0, cam.fy * iz,
        -cam.fy * x.y() * iz * iz;
    Eigen::Matrix3d minus_skew;
    minus_skew << 0.0, rotated.z(), -rotated.y(), -rotated.z(), 0.0, rotated.x(), rotated.y(),
        -rotated.x(), 0.0;
    Eigen::Matrix<double, 2, 6> J;
    J.leftCols<3>() = d_proj * minus_skew;
    J.rightCols<3>() = d_proj;
    // depth z = fx b / disparity: sigma_z = z^2 / (fx b) sigma_disparity, along the point's ray
    const double depth_sigma = p.z() * p.z() / (cam.fx * rig.baseline_m) * kDisparitySigmaPx;
    const Eigen::Vector2d moved = d_proj * (out.cur_from_prev.rotation * (p / p.z())) * depth_sigma;
    information += J.transpose() * J / (pixel_sq + moved.squaredNorm());
  }
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(information);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::nullopt;
  const Eigen::Matrix<double, 6, 6> covariance =
      ldlt.solve(Eigen::Matrix<double, 6, 6>::Identity());
  out.translation_covariance = covariance.bottomRightCorner<3, 3>();
  if (!out.translation_covariance.allFinite()) return std::nullopt;
  out.inliers = static_cast<int>(inliers.size());
  return out;
}

}  // namespace slslam
