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
// Corners are detected on the pyramid's half-size level (a quarter of the cost) over large
// blocks: smooth relief has its corners at that scale, and Lucas-Kanade places them on the full
// image.
constexpr double kCornerSpacingPx = 4.0;     // at half size [px]
constexpr int kCornerBlockPx = 15;           // at half size [px]
constexpr int kFlowWindowPx = 21;            // Lucas-Kanade window [px]
constexpr int kFlowLevels = 3;               // pyramid levels above the image [-]
constexpr int kFlowIterations = 10;          // on smooth shading more rarely converge further
constexpr float kMaxBackwardErrorPx = 0.5f;  // forward then backward track must return [px]
constexpr float kMaxRowOffsetPx = 1.0f;      // rectified stereo: same row [px]
// Depths beyond this many baselines are not used: their stereo depth's error biases the motion
// more than their flow constrains it (the lit end of a flat lining far ahead shortens the
// forward motion) [-]
constexpr double kMaxDepthBaselines = 60.0;
constexpr double kDisparitySigmaPx = 0.2;      // a Lucas-Kanade disparity's error [px]
constexpr float kRansacReprojectionPx = 1.0f;  // an inlier's reprojection error at most [px]
constexpr int kRansacIterations = 100;
constexpr double kRansacConfidence = 0.99;
constexpr double kMinReprojectionSigmaPx = 0.3;  // the covariance's floor on the residual [px]
constexpr double kMinDepthM = 1e-6;              // a point must stay in front of the camera [m]

const cv::Size kWindow(kFlowWindowPx, kFlowWindowPx);
const cv::TermCriteria kStop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, kFlowIterations,
                             0.01);

// The image scaled to `mean` grey (a flickering lamp is a gain), as a Lucas-Kanade pyramid;
// with its derivatives when it is a track's source image (only its levels otherwise).
std::vector<cv::Mat> Pyramid(const cv::Mat& grey, double mean, bool with_derivatives) {
  const double own = cv::mean(grey)[0];
  cv::Mat scaled;
  grey.convertTo(scaled, CV_8U, own > 1.0 ? mean / own : 1.0);
  std::vector<cv::Mat> pyramid;
  cv::buildOpticalFlowPyramid(scaled, pyramid, kWindow, kFlowLevels, with_derivatives);
  return pyramid;
}

struct Tracks {
  std::vector<cv::Point3f> points_prev;  ///< from stereo, in the previous left camera [m]
  std::vector<cv::Point2f> observed;     ///< in the current left image [px]
};

// Corners of the previous left pyramid into its right image (the same row, a depth within
// range), those into the current image and back.
Tracks TrackCorners(const std::vector<cv::Mat>& lp, const std::vector<cv::Mat>& rp,
                    const std::vector<cv::Mat>& lc, const StereoRig& rig) {
  Tracks out;
  std::vector<cv::Point2f> corners;
  // (index 2: the half-size image; 1 holds the full image's derivatives)
  cv::goodFeaturesToTrack(lp[2], corners, kMaxCorners, kCornerQuality, kCornerSpacingPx,
                          cv::noArray(), kCornerBlockPx);
  if (corners.empty()) return out;
  for (cv::Point2f& c : corners) c *= 2.0f;  // (the pyramid's half-size pixel u is at 2 u)
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
  if (stereo.empty()) return out;
  std::vector<cv::Point2f> in_cur, back;
  std::vector<unsigned char> back_ok;
  cv::calcOpticalFlowPyrLK(lp, lc, stereo, in_cur, ok, error, kWindow, kFlowLevels, kStop);
  cv::calcOpticalFlowPyrLK(lc, lp, in_cur, back, back_ok, error, kWindow, kFlowLevels, kStop);
  for (size_t i = 0; i < stereo.size(); ++i) {
    const cv::Point2f d = back[i] - stereo[i];
    if (!ok[i] || !back_ok[i] || !(d.dot(d) < kMaxBackwardErrorPx * kMaxBackwardErrorPx)) continue;
    const double z = cam.fx * rig.baseline_m / disparities[i];
    out.points_prev.emplace_back(static_cast<float>((stereo[i].x - cam.cx) * z / cam.fx),
                                 static_cast<float>((stereo[i].y - cam.cy) * z / cam.fy),
                                 static_cast<float>(z));
    out.observed.push_back(in_cur[i]);
  }
  return out;
}

// The covariance of cur_from_prev (left rotation perturbation, translation) from the inliers'
// Gauss-Newton information, each weighted by its reprojection's variance: the residuals' (at
// least kMinReprojectionSigmaPx) and its stereo depth's error moved into the current image.
// False when a point is behind the camera or the information is singular.
bool PoseCovariance(const Tracks& tracks, const std::vector<int>& inliers, const StereoRig& rig,
                    StereoFlowMotion* motion) {
  const PinholeCamera& cam = rig.camera;
  const Rigid3d& T = motion->cur_from_prev;
  double squared_sum = 0.0;
  for (const int i : inliers) {
    const cv::Point3f& q = tracks.points_prev[i];
    const Eigen::Vector3d x = T * Eigen::Vector3d(q.x, q.y, q.z);
    if (!(x.z() > kMinDepthM)) return false;
    squared_sum += Eigen::Vector2d(cam.fx * x.x() / x.z() + cam.cx - tracks.observed[i].x,
                                   cam.fy * x.y() / x.z() + cam.cy - tracks.observed[i].y)
                       .squaredNorm();
  }
  const int dof = std::max(1, 2 * static_cast<int>(inliers.size()) - 6);
  const double pixel_sq =
      std::max(kMinReprojectionSigmaPx * kMinReprojectionSigmaPx, squared_sum / dof);
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  for (const int i : inliers) {
    const cv::Point3f& q = tracks.points_prev[i];
    const Eigen::Vector3d p(q.x, q.y, q.z);
    const Eigen::Vector3d rotated = T.rotation * p;
    const Eigen::Vector3d x = rotated + T.translation;
    const double iz = 1.0 / x.z();
    Eigen::Matrix<double, 2, 3> d_proj;
    d_proj << cam.fx * iz, 0.0, -cam.fx * x.x() * iz * iz, 0.0, cam.fy * iz,
        -cam.fy * x.y() * iz * iz;
    Eigen::Matrix3d minus_skew;  // d(Exp(dtheta) R p) / d dtheta = -[R p]x
    minus_skew << 0.0, rotated.z(), -rotated.y(), -rotated.z(), 0.0, rotated.x(), rotated.y(),
        -rotated.x(), 0.0;
    Eigen::Matrix<double, 2, 6> J;
    J.leftCols<3>() = d_proj * minus_skew;
    J.rightCols<3>() = d_proj;
    // depth z = fx b / disparity: sigma_z = z^2 / (fx b) sigma_disparity, along the point's ray
    const double depth_sigma = p.z() * p.z() / (cam.fx * rig.baseline_m) * kDisparitySigmaPx;
    const Eigen::Vector2d moved = d_proj * (T.rotation * (p / p.z())) * depth_sigma;
    information += J.transpose() * J / (pixel_sq + moved.squaredNorm());
  }
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(information);
  // (isPositive accepts a singular matrix, whose solve zeroes the unobserved directions)
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return false;
  motion->covariance = ldlt.solve(Eigen::Matrix<double, 6, 6>::Identity());
  motion->covariance = 0.5 * (motion->covariance + motion->covariance.transpose());
  return motion->covariance.allFinite();
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
  // The other two at the previous left image's gain (none saturates more than it does).
  const double mean = cv::mean(left_prev)[0];
  // (the right image is only tracked into; the current one is tracked back from)
  const Tracks tracks =
      TrackCorners(Pyramid(left_prev, mean, true), Pyramid(right_prev, mean, false),
                   Pyramid(left_cur, mean, true), rig);
  const int needed = std::max(min_inliers, 6);
  if (static_cast<int>(tracks.points_prev.size()) < needed) return std::nullopt;
  cv::Mat K;
  cv::eigen2cv(rig.camera.K(), K);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  if (!cv::solvePnPRansac(tracks.points_prev, tracks.observed, K, cv::noArray(), rvec, tvec, false,
                          kRansacIterations, kRansacReprojectionPx, kRansacConfidence, inliers,
                          cv::SOLVEPNP_ITERATIVE) ||
      static_cast<int>(inliers.size()) < needed) {
    return std::nullopt;
  }
  cv::Mat R_cv;
  cv::Rodrigues(rvec, R_cv);
  StereoFlowMotion out;
  cv::cv2eigen(R_cv, out.cur_from_prev.rotation);
  cv::cv2eigen(tvec, out.cur_from_prev.translation);
  if (!out.cur_from_prev.rotation.allFinite() || !out.cur_from_prev.translation.allFinite() ||
      !PoseCovariance(tracks, inliers, rig, &out)) {
    return std::nullopt;
  }
  out.inliers = static_cast<int>(inliers.size());
  return out;
}

}  // namespace slslam
