#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings/image_conversion.h"
#include "slslam/features/dense_sampling.h"
#include "slslam/features/descriptor_matcher.h"
#include "slslam/features/dynamic_cell_filter.h"
#include "slslam/features/grid_limit.h"
#include "slslam/features/non_max_suppression.h"
#include "slslam/features/orb_extractor.h"

namespace py = pybind11;

namespace slslam::bindings {
void BindFeatures(py::module_& m) {
  py::class_<OrbOptions>(m, "OrbOptions",
                         "ORB extractor options (per-cell adaptive FAST, OpenCV descriptors).")
      .def(py::init<>())
      .def_readwrite("max_features", &OrbOptions::max_features)
      .def_readwrite("scale_factor", &OrbOptions::scale_factor)
      .def_readwrite("num_levels", &OrbOptions::num_levels)
      .def_readwrite("fast_threshold", &OrbOptions::fast_threshold)
      .def_readwrite("edge_threshold", &OrbOptions::edge_threshold)
      .def_readwrite("adaptive", &OrbOptions::adaptive)
      .def_readwrite("min_fast_threshold", &OrbOptions::min_fast_threshold)
      .def_readwrite("cell_size_px", &OrbOptions::cell_size_px)
      .def_readwrite("denoise_above_noise", &OrbOptions::denoise_above_noise)
      .def_readwrite("describe_smoothed", &OrbOptions::describe_smoothed)
      .def("check", &OrbOptions::Check);

  py::class_<MatchOptions>(m, "MatchOptions", "Brute-force matcher options.")
      .def(py::init<>())
      .def_readwrite("max_distance", &MatchOptions::max_distance)
      .def_readwrite("ratio", &MatchOptions::ratio)
      .def_readwrite("mutual", &MatchOptions::mutual)
      .def("check", &MatchOptions::Check);

  m.def(
      "extract_orb",
      [](const py::array& image, const OrbOptions& options) {
        const cv::Mat img = WrapGray(image, "image");
        Keypoints kp;
        {
          py::gil_scoped_release release;
          kp = ExtractOrb(img, options);
        }
        return py::make_tuple(kp.uv, kp.score, ToNumpy(kp.descriptors));
      },
      py::arg("image"), py::arg("options") = OrbOptions{},
      "ORB keypoints of a uint8 image: (uv float32 N x 2, score float32 N, descriptors uint8 N x "
      "32).");

  m.def(
      "estimate_noise_sigma",
      [](const py::array& image) {
        const cv::Mat img = WrapGray(image, "image");
        py::gil_scoped_release release;
        return EstimateNoiseSigma(img);
      },
      py::arg("image"),
      "Standard deviation of white noise in a uint8 gray image [gray levels] (Immerkaer 1996: "
      "the 3 x 3 mask [1 -2 1]^T [1 -2 1], the L1 norm of its response over the inner pixels).");

  m.def(
      "smooth_if_noisy",
      [](const py::array& image, double above_noise) -> py::array {
        const cv::Mat img = WrapGray(image, "image");
        cv::Mat out;
        {
          py::gil_scoped_release release;
          out = SmoothIfNoisy(img, above_noise);
        }
        return out.data == img.data ? image : ToNumpy(out);
      },
      py::arg("image"), py::arg("above_noise"),
      "The uint8 image smoothed by a Gaussian of sigma = noise / 7 px when its estimated noise "
      "(Immerkaer) exceeds above_noise (> 0): a new array; otherwise the image itself.");

  m.def(
      "match_descriptors",
      [](const py::array& query, const py::array& train, const MatchOptions& options) {
        const cv::Mat q = WrapDescriptors(query), t = WrapDescriptors(train);
        py::gil_scoped_release release;
        return MatchDescriptors(q, t, options);
      },
      py::arg("query"), py::arg("train"), py::arg("options") = MatchOptions{},
      "Mutual nearest-neighbour + ratio matching; returns (query index, train index) pairs N x 2.");

  py::class_<GridLimitOptions>(m, "GridLimitOptions",
                               "Per-cell keypoint limit (the SL-SLAM paper's grid limitation).")
      .def(py::init<>())
      .def_readwrite("cell_size_px", &GridLimitOptions::cell_size_px, "cell side P [px]")
      .def_readwrite("max_per_cell", &GridLimitOptions::max_per_cell, "keypoints kept per cell")
      .def_readwrite("strong_score", &GridLimitOptions::strong_score,
                     "cells with a keypoint at this score keep only such keypoints; "
                     "-inf: off")
      .def("check", &GridLimitOptions::Check);
  m.def(
      "grid_limit",
      [](const PixelArray& uv, const Eigen::VectorXf& score, int width, int height,
         const GridLimitOptions& options) {
        py::gil_scoped_release release;
        return GridLimit(uv, score, width, height, options);
      },
      py::arg("uv"), py::arg("score"), py::arg("width"), py::arg("height"),
      py::arg("options") = GridLimitOptions{},
      "Indices (ascending) of the keypoints kept: the best max_per_cell by score in every cell.");

  py::class_<DynamicCellOptions>(m, "DynamicCellOptions",
                                 "Invalid-cell filter (the SL-SLAM paper's).")
      .def(py::init<>())
      .def_readwrite("cell_size_px", &DynamicCellOptions::cell_size_px, "cell side [px]")
      .def_readwrite("sigma_px", &DynamicCellOptions::sigma_px, "Gaussian width of G(d) [px]")
      .def_readwrite("alpha", &DynamicCellOptions::alpha, "weight of the current frame")
      .def_readwrite("threshold", &DynamicCellOptions::threshold, "l: invalid below this")
      .def_readwrite("min_matches", &DynamicCellOptions::min_matches,
                     "matches a cell needs in a frame to count as evidence")
      .def_readwrite("sigma_median_ratio", &DynamicCellOptions::sigma_median_ratio,
                     "G's width is at least this many times the frame's median match residual")
      .def("check", &DynamicCellOptions::Check);
  py::class_<DynamicCellFilter>(m, "DynamicCellFilter",
                                "Per-cell motion-consistency weights; drops moving objects.")
      .def(py::init<int, int, const DynamicCellOptions&>(), py::arg("width"), py::arg("height"),
           py::arg("options") = DynamicCellOptions{})
      .def("update", &DynamicCellFilter::Update, py::arg("observed"), py::arg("predicted"),
           "Update from matched positions and their motion-predicted positions (M x 2 each); "
           "returns the validity of every cell (row-major).")
      .def("keypoint_mask", &DynamicCellFilter::KeypointMask, py::arg("uv"))
      .def_property_readonly("weights", &DynamicCellFilter::weights)
      .def_property_readonly("valid", &DynamicCellFilter::valid)
      .def_property_readonly("cells_x", &DynamicCellFilter::cells_x)
      .def_property_readonly("cells_y", &DynamicCellFilter::cells_y)
      .def("reset", &DynamicCellFilter::Reset);
  m.def(
      "predict_with_robust_pose",
      [](const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& points_prev,
         const PixelArray& observed, const PinholeCamera& camera, double threshold_px) {
        RobustPrediction r = PredictWithRobustPose(points_prev, observed, camera, threshold_px);
        return py::make_tuple(r.ok, r.predicted, r.T_cur_prev, r.inliers);
      },
      py::arg("points_prev"), py::arg("observed"), py::arg("camera"), py::arg("threshold_px") = 2.0,
      "RANSAC PnP pose from 3-D points (previous camera frame) and their current pixels; returns "
      "(ok, predicted uv N x 2, T_cur_prev 4 x 4, inlier flags).");

  py::class_<GuidedMatchOptions>(m, "GuidedMatchOptions", "Window-guided descriptor matching.")
      .def(py::init<>())
      .def_readwrite("radius_px", &GuidedMatchOptions::radius_px, "search radius [px]")
      .def_readwrite("max_distance", &GuidedMatchOptions::max_distance, "descriptor distance")
      .def_readwrite("ratio", &GuidedMatchOptions::ratio, "ratio test in the window")
      .def("check", &GuidedMatchOptions::Check);
  m.def(
      "guided_match",
      [](const PixelArray& predicted, const py::array& query, const PixelArray& keypoints,
         const py::array& train, const GuidedMatchOptions& options) {
        const cv::Mat q = WrapDescriptors(query), t = WrapDescriptors(train);
        py::gil_scoped_release release;
        return GuidedMatch(predicted, q, keypoints, t, options);
      },
      py::arg("predicted"), py::arg("query"), py::arg("keypoints"), py::arg("train"),
      py::arg("options") = GuidedMatchOptions{},
      "For each predicted position (M x 2) with descriptor, the index of the best keypoint within "
      "the radius, or -1.");

  m.def(
      "suppress_non_maxima",
      [](const PixelIndexArray& uv, const Eigen::VectorXf& score, int width, int height,
         int radius_px) {
        py::gil_scoped_release release;
        return SuppressNonMaxima(uv, score, width, height, radius_px);
      },
      py::arg("uv"), py::arg("score"), py::arg("width"), py::arg("height"), py::arg("radius_px"),
      "Greedy NMS of integer (u, v) candidates (N x 2 int32): kept indices, strongest first.");
  m.def(
      "sample_dense_map",
      [](const Eigen::Ref<const DenseSamples>& map, int map_height, int map_width,
         const PixelArray& uv, int input_height, int input_width, bool cubic) {
        py::gil_scoped_release release;  // map refers to the caller's array, alive for the call
        return SampleDenseMap(map, map_height, map_width, uv, input_height, input_width, cubic);
      },
      py::arg("map"), py::arg("map_height"), py::arg("map_width"), py::arg("uv"),
      py::arg("input_height"), py::arg("input_width"), py::arg("cubic"),
      "Samples of a C x (Hc Wc) float32 map at input pixels uv (N x 2), as grid_sample "
      "(align_corners=False, zero padding), bilinear or bicubic: N x C.");
  m.def(
      "local_maxima",
      [](const Eigen::Ref<const HeatMap>& heat, float threshold, int radius_px, int border_px) {
        py::gil_scoped_release release;  // heat refers to the caller's array, alive for the call
        return LocalMaxima(heat, threshold, radius_px, border_px);
      },
      py::arg("heat"), py::arg("threshold"), py::arg("radius_px"), py::arg("border_px"),
      "Max-filter NMS of a float32 heatmap (H x W): (u, v) int32 of the pixels above the "
      "threshold that are the maximum of their (2r+1)^2 window (ties kept), row-major order.");
}

}  // namespace slslam::bindings
