#include "slslam/features/dynamic_cell_filter.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "slslam/core/check.h"

namespace slslam {

void DynamicCellOptions::Check() const {
  CheckInRange("dynamic.cell_size_px", cell_size_px, 4, limits::kMaxCellSizePx);
  CheckAboveInRange("dynamic.sigma_px", sigma_px, 0.0, 1e6);
  CheckAboveInRange("dynamic.alpha", alpha, 0.0, 1.0);
  CheckInRange("dynamic.threshold", threshold, 0.0, 1.0);
  CheckInRange("dynamic.min_matches", min_matches, 1, 1000000);
  CheckInRange("dynamic.sigma_median_ratio", sigma_median_ratio, 0.0, 1000.0);
}

DynamicCellFilter::DynamicCellFilter(int width, int height, const DynamicCellOptions& options)
    : options_(options), width_(width), height_(height) {
  options_.Check();
  SLSLAM_CHECK(width > 0 && height > 0, "image size must be positive, got ", width, "x", height);
  cells_x_ = (width + options_.cell_size_px - 1) / options_.cell_size_px;
  cells_y_ = (height + options_.cell_size_px - 1) / options_.cell_size_px;
  Reset();
}

void DynamicCellFilter::Reset() {
  weights_.assign(static_cast<size_t>(cells_x_) * cells_y_, 1.0);
  valid_.assign(weights_.size(), true);
}

int DynamicCellFilter::CellOf(float u, float v) const {
  if (!(u >= 0.0f && v >= 0.0f && u < width_ && v < height_)) return -1;
  return static_cast<int>(v) / options_.cell_size_px * cells_x_ +
         static_cast<int>(u) / options_.cell_size_px;
}

const std::vector<bool>& DynamicCellFilter::Update(const PixelArray& observed,
                                                   const PixelArray& predicted) {
  SLSLAM_CHECK(observed.rows() == predicted.rows(), observed.rows(), " observed but ",
               predicted.rows(), " predicted positions");
  std::vector<std::vector<double>> distances(weights_.size());
  for (Eigen::Index i = 0; i < observed.rows(); ++i) {
    const int c = CellOf(observed(i, 0), observed(i, 1));
    const double d = (observed.row(i) - predicted.row(i)).cast<double>().norm();
    if (c < 0 || !std::isfinite(d)) continue;
    distances[c].push_back(d);
  }
  // G's width: sigma_px, or with sigma_median_ratio > 0 more when the frame's matches are noisy
  // as a whole. A front end whose keypoints repeat less precisely (XFeat: a median frame-to-frame
  // residual of about 2 px against ORB's 1 px on the simulated loop) otherwise flags most static
  // cells: on the bright simulated loop the fixed width masked most of XFeat's keypoints. A mover
  // still stands out against the consensus of the frame. ORB keeps the fixed width: on the dark
  // dusty sequences it tracked better with it (benchmarks/log/realtime.md).
  double sigma = options_.sigma_px;
  if (options_.sigma_median_ratio > 0.0) {
    std::vector<double> all;
    for (const std::vector<double>& ds : distances) all.insert(all.end(), ds.begin(), ds.end());
    if (!all.empty()) {
      std::nth_element(all.begin(), all.begin() + all.size() / 2, all.end());
      sigma = std::max(sigma, options_.sigma_median_ratio * all[all.size() / 2]);
    }
  }
  const double two_sigma2 = 2.0 * sigma * sigma;
  for (size_t c = 0; c < weights_.size(); ++c) {
    // d: the median distance of the cell's matches (the paper's mean lets one or two mismatches
    // in repetitive texture, mesh or arches, flag a static cell; a mover shifts all its points).
    // No match in the cell: nothing disagrees with the motion (G = 1), so a cell the mover has
    // left recovers instead of staying invalid.
    std::vector<double>& ds = distances[c];
    double d = 0.0;
    if (static_cast<int>(ds.size()) >= options_.min_matches) {
      const size_t mid = ds.size() / 2;
      std::nth_element(ds.begin(), ds.begin() + mid, ds.end());
      d = ds[mid];
      if (ds.size() % 2 == 0) d = 0.5 * (d + *std::max_element(ds.begin(), ds.begin() + mid));
    }
    weights_[c] =
        options_.alpha * std::exp(-d * d / two_sigma2) + (1.0 - options_.alpha) * weights_[c];
  }
  valid_.assign(weights_.size(), true);
  for (int cy = 0; cy < cells_y_; ++cy) {
    for (int cx = 0; cx < cells_x_; ++cx) {
      if (weights_[cy * cells_x_ + cx] >= options_.threshold) continue;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = cx + dx, y = cy + dy;
          if (x >= 0 && y >= 0 && x < cells_x_ && y < cells_y_) valid_[y * cells_x_ + x] = false;
        }
      }
    }
  }
  return valid_;
}

std::vector<bool> DynamicCellFilter::KeypointMask(const PixelArray& uv) const {
  std::vector<bool> mask(uv.rows(), false);
  for (Eigen::Index i = 0; i < uv.rows(); ++i) {
    const int c = CellOf(uv(i, 0), uv(i, 1));
    mask[i] = c >= 0 && valid_[c];
  }
  return mask;
}

RobustPrediction PredictWithRobustPose(
    const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& points_prev,
    const PixelArray& observed, const PinholeCamera& camera, double reprojection_threshold_px) {
  camera.Check();
  SLSLAM_CHECK(points_prev.rows() == observed.rows(), points_prev.rows(), " points but ",
               observed.rows(), " observations");
  RobustPrediction out;
  out.T_cur_prev.setIdentity();
  if (points_prev.rows() < 6) return out;  // too few for a trustworthy RANSAC pose
  std::vector<cv::Point3d> object(points_prev.rows());
  std::vector<cv::Point2d> image(observed.rows());
  for (Eigen::Index i = 0; i < points_prev.rows(); ++i) {
    object[i] = {points_prev(i, 0), points_prev(i, 1), points_prev(i, 2)};
    image[i] = {observed(i, 0), observed(i, 1)};
  }
  cv::Mat K;
  cv::eigen2cv(camera.K(), K);
  cv::Mat rvec, tvec;
  std::vector<int> inlier_ids;
  const bool ok = cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false, 200,
                                     static_cast<float>(reprojection_threshold_px), 0.999,
                                     inlier_ids, cv::SOLVEPNP_EPNP);
  if (!ok || inlier_ids.size() < 6) return out;
  // Refine on the inliers only (Levenberg-Marquardt), so the moving block cannot pull the pose.
  std::vector<cv::Point3d> in_object;
  std::vector<cv::Point2d> in_image;
  for (int i : inlier_ids) {
    in_object.push_back(object[i]);
    in_image.push_back(image[i]);
  }
  cv::solvePnPRefineLM(in_object, in_image, K, cv::noArray(), rvec, tvec);
  std::vector<cv::Point2d> projected;
  cv::projectPoints(object, rvec, tvec, K, cv::noArray(), projected);
  out.predicted.resize(observed.rows(), 2);
  for (Eigen::Index i = 0; i < observed.rows(); ++i) {
    out.predicted(i, 0) = static_cast<float>(projected[i].x);
    out.predicted(i, 1) = static_cast<float>(projected[i].y);
  }
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d R_e;
  Eigen::Vector3d t_e;
  cv::cv2eigen(R, R_e);
  cv::cv2eigen(tvec, t_e);
  out.T_cur_prev.topLeftCorner<3, 3>() = R_e;
  out.T_cur_prev.topRightCorner<3, 1>() = t_e;
  out.inliers.assign(observed.rows(), false);
  for (int i : inlier_ids) out.inliers[i] = true;
  out.ok = true;
  return out;
}

}  // namespace slslam
