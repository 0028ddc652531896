// Keypoints as plain arrays: the form every point front end (ORB here, SuperPoint in Python)
// hands to the tracker.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace slslam {

struct Keypoints {
  Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor> uv;  ///< pixel positions (u, v) [px]
  Eigen::VectorXf score;   ///< detector response, larger is stronger [-]
  Eigen::VectorXi octave;  ///< pyramid level the keypoint was found on (0 = full resolution)
  cv::Mat descriptors;     ///< one row per keypoint; CV_8U (binary) or CV_32F (float)

  int size() const { return static_cast<int>(uv.rows()); }
};

}  // namespace slslam
