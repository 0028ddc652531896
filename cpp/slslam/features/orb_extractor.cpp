#include "slslam/features/orb_extractor.h"

#include <vector>

#include <opencv2/features2d.hpp>

#include "slslam/core/check.h"

namespace slslam {

void OrbOptions::Check() const {
  Require(max_features > 0, Message("orb.max_features must be > 0, got ", max_features));
  Require(scale_factor > 1.0f, Message("orb.scale_factor must be > 1, got ", scale_factor));
  Require(num_levels >= 1, Message("orb.num_levels must be >= 1, got ", num_levels));
  Require(fast_threshold > 0, Message("orb.fast_threshold must be > 0, got ", fast_threshold));
  Require(edge_threshold >= 0, Message("orb.edge_threshold must be >= 0, got ", edge_threshold));
}

Keypoints ExtractOrb(const cv::Mat& image, const OrbOptions& options) {
  options.Check();
  Require(!image.empty() && image.type() == CV_8UC1, "ORB needs a non-empty 8-bit gray image");
  auto orb = cv::ORB::create(options.max_features, options.scale_factor, options.num_levels,
                             options.edge_threshold, 0, 2, cv::ORB::HARRIS_SCORE,
                             /*patchSize=*/31, options.fast_threshold);
  std::vector<cv::KeyPoint> cv_keypoints;
  Keypoints out;
  orb->detectAndCompute(image, cv::noArray(), cv_keypoints, out.descriptors);
  const int n = static_cast<int>(cv_keypoints.size());
  out.uv.resize(n, 2);
  out.score.resize(n);
  out.octave.resize(n);
  for (int i = 0; i < n; ++i) {
    out.uv(i, 0) = cv_keypoints[i].pt.x;
    out.uv(i, 1) = cv_keypoints[i].pt.y;
    out.score(i) = cv_keypoints[i].response;
    out.octave(i) = cv_keypoints[i].octave;
  }
  if (n == 0) out.descriptors = cv::Mat(0, 32, CV_8U);
  return out;
}

}  // namespace slslam
