// slslam._core line front end: LSD + LBD, preprocessing, point-line association, line matching.
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings/image_conversion.h"
#include "slslam/features/line_extractor.h"
#include "slslam/features/line_matcher.h"
#include "slslam/features/lsd.h"
#include "slslam/features/point_line_association.h"

namespace py = pybind11;

namespace slslam::bindings {
namespace {

using SegmentArray = Eigen::Matrix<float, Eigen::Dynamic, 4, Eigen::RowMajor>;

Segments ToSegments(const SegmentArray& a) {
  Segments out(a.rows());
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    out[i] = {{a(i, 0), a(i, 1)}, {a(i, 2), a(i, 3)}};
  }
  return out;
}

SegmentArray ToArray(const Segments& s) {
  SegmentArray out(static_cast<Eigen::Index>(s.size()), 4);
  for (size_t i = 0; i < s.size(); ++i) {
    out.row(i) << s[i].start.x(), s[i].start.y(), s[i].end.x(), s[i].end.y();
  }
  return out;
}

cv::Mat WrapLbd(const py::array& a, const char* what) {
  const cv::Mat d = WrapDescriptors(a);
  if (d.type() != CV_8U || (d.rows > 0 && d.cols != 32)) {
    throw py::value_error(std::string(what) + " must be a C-contiguous uint8 (N, 32) LBD array");
  }
  return d;
}

}  // namespace

void BindLines(py::module_& m) {
  py::class_<LinePreprocessOptions>(m, "LinePreprocessOptions",
                                    "Line preprocessing (the SL-SLAM paper's).")
      .def(py::init<>())
      .def_readwrite("length_ratio", &LinePreprocessOptions::length_ratio, "zeta")
      .def_readwrite("theta_min_rad", &LinePreprocessOptions::theta_min_rad, "angle unit [rad]")
      .def_readwrite("xi_d_px", &LinePreprocessOptions::xi_d_px, "merge/delete distance [px]")
      .def_readwrite("max_gap_px", &LinePreprocessOptions::max_gap_px, "gap limit [px]")
      .def("check", &LinePreprocessOptions::Check);
  py::class_<AssociationOptions>(m, "AssociationOptions",
                                 "Point-line association (the SL-SLAM paper's).")
      .def(py::init<>())
      .def_readwrite("cell_size_px", &AssociationOptions::cell_size_px)
      .def_readwrite("layers", &AssociationOptions::layers)
      .def_readwrite("max_distance_px", &AssociationOptions::max_distance_px)
      .def("check", &AssociationOptions::Check);
  py::class_<LineMatchOptions>(m, "LineMatchOptions", "Point-driven line matching.")
      .def(py::init<>())
      .def_readwrite("min_votes", &LineMatchOptions::min_votes)
      .def_readwrite("max_lbd_distance", &LineMatchOptions::max_lbd_distance)
      .def_readwrite("max_angle_rad", &LineMatchOptions::max_angle_rad)
      .def("check", &LineMatchOptions::Check);
  py::class_<StereoLineOptions>(m, "StereoLineOptions", "Stereo line matching.")
      .def(py::init<>())
      .def_readwrite("min_row_overlap", &StereoLineOptions::min_row_overlap)
      .def_readwrite("max_lbd_distance", &StereoLineOptions::max_lbd_distance)
      .def_readwrite("max_angle_rad", &StereoLineOptions::max_angle_rad)
      .def_readwrite("min_angle_from_horizontal_rad",
                     &StereoLineOptions::min_angle_from_horizontal_rad)
      .def_readwrite("min_disparity_px", &StereoLineOptions::min_disparity_px)
      .def("check", &StereoLineOptions::Check);

  py::class_<LbdOptions>(m, "LbdOptions", "Our line band descriptor (features/lbd.h).")
      .def(py::init<>())
      .def_readwrite("band_width_px", &LbdOptions::band_width_px)
      .def_readwrite("max_samples_along", &LbdOptions::max_samples_along)
      .def_readwrite("smoothing_sigma_px", &LbdOptions::smoothing_sigma_px)
      .def("check", &LbdOptions::Check);
  py::class_<LineExtractorOptions>(m, "LineExtractorOptions",
                                   "Line front end of the tracker: detector, scale, preprocessing, "
                                   "cap (tracking.line_* keys).")
      .def(py::init<>())
      .def_readwrite("preprocess", &LineExtractorOptions::preprocess)
      .def_readwrite("detection_scale", &LineExtractorOptions::detection_scale)
      .def_readwrite("max_lines", &LineExtractorOptions::max_lines)
      .def_property(
          "detector", [](const LineExtractorOptions& o) { return LineDetectorName(o.detector); },
          [](LineExtractorOptions& o, const std::string& name) {
            o.detector = ParseLineDetector(name);
          },
          "lsd (ours), lsd_opencv (OpenCV's) or fld")
      .def_property(
          "descriptor",
          [](const LineExtractorOptions& o) { return LineDescriptorName(o.descriptor); },
          [](LineExtractorOptions& o, const std::string& name) {
            o.descriptor = ParseLineDescriptor(name);
          },
          "lbd (ours) or opencv_lbd (OpenCV's BinaryDescriptor's bytes)")
      .def_readwrite("lbd", &LineExtractorOptions::lbd)
      .def("check", &LineExtractorOptions::Check);

  m.def(
      "detect_lsd_segments",
      [](const py::array& image) {
        const cv::Mat img = WrapGray(image, "image");
        std::vector<cv::Vec4f> raw;
        {
          py::gil_scoped_release release;
          raw = DetectLsdSegments(img);
        }
        SegmentArray out(static_cast<Eigen::Index>(raw.size()), 4);
        for (std::size_t i = 0; i < raw.size(); ++i) {
          out.row(i) << raw[i][0], raw[i][1], raw[i][2], raw[i][3];
        }
        return out;
      },
      py::arg("image"),
      "LSD's raw segments (x1, y1, x2, y2) of an 8-bit gray image, with LSD's default settings "
      "(features/lsd.h): before preprocessing, at the image's resolution.");
  m.def(
      "extract_lines",
      [](const py::array& image, const LineExtractorOptions& options) {
        const cv::Mat img = WrapGray(image, "image");
        LineFeatures f;
        {
          py::gil_scoped_release release;
          f = ExtractLines(img, options);
        }
        return py::make_tuple(ToArray(f.segments), ToNumpy(f.descriptors), f.raw_count);
      },
      py::arg("image"), py::arg("options") = LineExtractorOptions{},
      "Segments + preprocessing + LBD with the tracker's line options (detector, detection "
      "scale, cap): (segments float32 (N, 4) as u0 v0 u1 v1, LBD uint8 (N, 32), number of raw "
      "segments).");
  m.def(
      "preprocess_lines",
      [](const SegmentArray& segments, int width, int height,
         const LinePreprocessOptions& options) {
        return ToArray(PreprocessLines(ToSegments(segments), width, height, options));
      },
      py::arg("segments"), py::arg("width"), py::arg("height"),
      py::arg("options") = LinePreprocessOptions{});
  m.def(
      "associate_points_to_lines",
      [](const PixelArray& keypoints, const SegmentArray& segments, int width, int height,
         const AssociationOptions& options, const std::vector<bool>& valid_cells) {
        py::gil_scoped_release release;
        return AssociatePointsToLines(keypoints, ToSegments(segments), width, height, options,
                                      valid_cells);
      },
      py::arg("keypoints"), py::arg("segments"), py::arg("width"), py::arg("height"),
      py::arg("options") = AssociationOptions{}, py::arg("valid_cells") = std::vector<bool>{},
      "For every segment, the indices of its associated keypoints.");
  m.def(
      "match_lines_by_points",
      [](const SegmentArray& lines_a, const std::vector<std::vector<int>>& points_a,
         const py::array& lbd_a, const SegmentArray& lines_b,
         const std::vector<std::vector<int>>& points_b, const py::array& lbd_b,
         const IndexPairs& point_matches, const LineMatchOptions& options) {
        const cv::Mat da = WrapLbd(lbd_a, "lbd_a"), db = WrapLbd(lbd_b, "lbd_b");
        py::gil_scoped_release release;
        return MatchLinesByPoints(ToSegments(lines_a), points_a, da, ToSegments(lines_b), points_b,
                                  db, point_matches, options);
      },
      py::arg("lines_a"), py::arg("points_a"), py::arg("lbd_a"), py::arg("lines_b"),
      py::arg("points_b"), py::arg("lbd_b"), py::arg("point_matches"),
      py::arg("options") = LineMatchOptions{});
  m.def(
      "match_stereo_lines",
      [](const SegmentArray& left, const py::array& lbd_left, const SegmentArray& right,
         const py::array& lbd_right, const StereoLineOptions& options) {
        const cv::Mat dl = WrapLbd(lbd_left, "lbd_left"), dr = WrapLbd(lbd_right, "lbd_right");
        py::gil_scoped_release release;
        return MatchStereoLines(ToSegments(left), dl, ToSegments(right), dr, options);
      },
      py::arg("left"), py::arg("lbd_left"), py::arg("right"), py::arg("lbd_right"),
      py::arg("options") = StereoLineOptions{});
  m.def(
      "triangulate_stereo_lines",
      [](const SegmentArray& left, const SegmentArray& right, const PinholeCamera& camera,
         double baseline_m) {
        if (left.rows() != right.rows()) throw py::value_error("left and right differ in length");
        const Segments l = ToSegments(left), r = ToSegments(right);
        Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> points(left.rows(), 6);
        std::vector<bool> ok(left.rows(), false);
        points.setConstant(std::numeric_limits<double>::quiet_NaN());
        for (Eigen::Index i = 0; i < left.rows(); ++i) {
          Eigen::Vector3d s, e;
          if (TriangulateStereoLine(l[i], r[i], camera, baseline_m, &s, &e)) {
            points.row(i) << s.transpose(), e.transpose();
            ok[i] = true;
          }
        }
        return py::make_tuple(points, ok);
      },
      py::arg("left"), py::arg("right"), py::arg("camera"), py::arg("baseline_m"),
      "3-D endpoints (N, 6: start xyz, end xyz in the left camera [m]) and success flags.");
}

}  // namespace slslam::bindings
