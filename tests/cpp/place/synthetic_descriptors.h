// Clustered synthetic descriptors shared by the vocabulary and keyframe-database tests: cluster
// centres far apart, members a few bits (binary) or a small Gaussian step (float) away.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include <opencv2/core.hpp>

namespace slslam::test {

struct ClusteredDescriptors {
  int type = CV_8U;
  int cols = 32;
  std::vector<cv::Mat> centres;  // one 1 x cols row per cluster
  std::mt19937 rng{7};

  // `count` clusters of CV_8U x cols (random bytes) or CV_32F x cols (uniform in [0, 10)).
  ClusteredDescriptors(int cluster_count, int descriptor_type, int descriptor_cols,
                       unsigned seed = 7)
      : type(descriptor_type), cols(descriptor_cols), rng(seed) {
    for (int c = 0; c < cluster_count; ++c) {
      cv::Mat centre(1, cols, type);
      for (int j = 0; j < cols; ++j) {
        if (type == CV_8U) {
          centre.at<uint8_t>(0, j) = static_cast<uint8_t>(rng() & 0xFF);
        } else {
          centre.at<float>(0, j) = std::uniform_real_distribution<float>(0.f, 10.f)(rng);
        }
      }
      centres.push_back(centre);
    }
  }

  // A member of `cluster`: up to `noise_bits` flipped bits (binary) or Gaussian noise of
  // `noise_bits` * 0.05 per dimension (float); noise_bits = 0 copies the centre.
  cv::Mat Member(int cluster, int noise_bits = 3) {
    cv::Mat row = centres[cluster].clone();
    if (type == CV_8U) {
      for (int b = 0; b < noise_bits; ++b) {
        const int bit = static_cast<int>(rng() % (8 * cols));
        row.at<uint8_t>(0, bit / 8) ^= static_cast<uint8_t>(1u << (bit % 8));
      }
    } else if (noise_bits > 0) {
      std::normal_distribution<float> noise(0.f, 0.05f * noise_bits);
      for (int j = 0; j < cols; ++j) row.at<float>(0, j) += noise(rng);
    }
    return row;
  }

  // An image: `per_cluster` members of each cluster in `clusters`, stacked as rows.
  cv::Mat Image(const std::vector<int>& clusters, int per_cluster, int noise_bits = 3) {
    cv::Mat image;
    for (const int c : clusters) {
      for (int i = 0; i < per_cluster; ++i) image.push_back(Member(c, noise_bits));
    }
    return image;
  }
};

}  // namespace slslam::test
