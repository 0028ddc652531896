#include "slslam/features/line_extractor.h"

#include <algorithm>

#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc/fast_line_detector.hpp>

#include "slslam/core/check.h"
#include "slslam/features/lsd.h"
#include "slslam/features/opencv_lbd.h"

namespace slslam {

namespace {

// FastLineDetector settings: OpenCV's defaults (segments from 10 px, 1.414 px off the fit line,
// Canny 50 / 50 with a 3 x 3 Sobel) without its merging step, which compares every pair of
// segments (0.7 s against 40 ms without it on a textured simulated 752 x 480 frame, loaded
// machine); preprocessing merges collinear pieces anyway.
constexpr int kFldMinLengthPx = 10;
constexpr float kFldMaxDistancePx = 1.414f;
constexpr double kFldCannyLow = 50.0, kFldCannyHigh = 50.0;
constexpr int kFldCannyAperture = 3;

void DetectSegments(const cv::Mat& image, LineDetector detector, std::vector<cv::Vec4f>* raw) {
  if (detector == LineDetector::kFld) {
    cv::ximgproc::createFastLineDetector(kFldMinLengthPx, kFldMaxDistancePx, kFldCannyLow,
                                         kFldCannyHigh, kFldCannyAperture, false)
        ->detect(image, *raw);
  } else if (detector == LineDetector::kOpenCvLsd) {
    cv::createLineSegmentDetector(cv::LSD_REFINE_STD)->detect(image, *raw);
  } else {
    *raw = DetectLsdSegments(image);
  }
}

}  // namespace

cv::Mat ComputeLineDescriptors(const cv::Mat& image, const Segments& segments,
                               LineDescriptor descriptor, const LbdOptions& lbd) {
  Require(!image.empty() && image.type() == CV_8UC1, "LBD needs a non-empty 8-bit gray image");
  if (descriptor == LineDescriptor::kLbd) return ComputeBandDescriptors(image, segments, lbd);
  return ComputeOpenCvCompatibleLbd(image, segments);
}

LineDetector ParseLineDetector(const std::string& name) {
  if (name == "lsd") return LineDetector::kLsd;
  if (name == "fld") return LineDetector::kFld;
  if (name == "lsd_opencv") return LineDetector::kOpenCvLsd;
  SLSLAM_CHECK(false, "line detector must be lsd, lsd_opencv or fld, got '", name, "'");
  return LineDetector::kLsd;
}

std::string LineDetectorName(LineDetector detector) {
  if (detector == LineDetector::kFld) return "fld";
  return detector == LineDetector::kOpenCvLsd ? "lsd_opencv" : "lsd";
}

void LineExtractorOptions::Check() const {
  preprocess.Check();
  lbd.Check();
  CheckAboveInRange("lines.detection_scale", detection_scale, 0.0f, 1.0f);
  SLSLAM_CHECK(max_lines >= 0, "lines.max_lines must be >= 0 (0: all), got ", max_lines);
}

LineFeatures ExtractLines(const cv::Mat& image, const LineExtractorOptions& options) {
  options.Check();
  Require(!image.empty() && image.type() == CV_8UC1, "LSD needs a non-empty 8-bit gray image");
  std::vector<cv::Vec4f> raw;
  const float scale = options.detection_scale;
  cv::Mat detect_on = image;
  if (scale < 1.0f) {
    const cv::Size size(std::max(1, static_cast<int>(std::lround(image.cols * scale))),
                        std::max(1, static_cast<int>(std::lround(image.rows * scale))));
    cv::resize(image, detect_on, size, 0, 0, cv::INTER_AREA);
  }
  DetectSegments(detect_on, options.detector, &raw);
  // Pixel centres: x_full = (x_small + 0.5) * cols / small_cols - 0.5 (same for rows).
  const float sx = static_cast<float>(image.cols) / detect_on.cols;
  const float sy = static_cast<float>(image.rows) / detect_on.rows;
  const auto full = [&](float x, float y) {
    return Eigen::Vector2f((x + 0.5f) * sx - 0.5f, (y + 0.5f) * sy - 0.5f);
  };
  Segments segments;
  segments.reserve(raw.size());
  for (const cv::Vec4f& l : raw) segments.push_back({full(l[0], l[1]), full(l[2], l[3])});
  LineFeatures out;
  out.raw_count = static_cast<int>(segments.size());
  out.segments = options.run_preprocess
                     ? PreprocessLines(segments, image.cols, image.rows, options.preprocess)
                     : segments;
  if (options.max_lines > 0 && static_cast<int>(out.segments.size()) > options.max_lines) {
    if (!options.run_preprocess) {  // preprocessing returns them longest first
      std::stable_sort(
          out.segments.begin(), out.segments.end(),
          [](const LineSegment& a, const LineSegment& b) { return a.Length() > b.Length(); });
    }
    out.segments.resize(options.max_lines);
  }
  // Keep segments within the image so LBD's bands stay valid.
  Segments inside;
  for (const LineSegment& s : out.segments) {
    LineSegment c = s;
    for (Eigen::Vector2f* p : {&c.start, &c.end}) {
      p->x() = std::clamp(p->x(), 0.0f, image.cols - 1.0f);
      p->y() = std::clamp(p->y(), 0.0f, image.rows - 1.0f);
    }
    if (c.Length() > 1.0f) inside.push_back(c);
  }
  out.segments = std::move(inside);
  // Ours on the image LSD ran on (the segments mapped onto it), OpenCV's at full resolution.
  const bool on_detection_image = options.descriptor == LineDescriptor::kLbd;
  Segments scaled;
  if (on_detection_image) {
    scaled.reserve(out.segments.size());
    const auto small = [&](const Eigen::Vector2f& p) {
      return Eigen::Vector2f((p.x() + 0.5f) / sx - 0.5f, (p.y() + 0.5f) / sy - 0.5f);
    };
    for (const LineSegment& s : out.segments) scaled.push_back({small(s.start), small(s.end)});
  }
  out.descriptors = ComputeLineDescriptors(on_detection_image ? detect_on : image,
                                           on_detection_image ? scaled : out.segments,
                                           options.descriptor, options.lbd);
  return out;
}

}  // namespace slslam
