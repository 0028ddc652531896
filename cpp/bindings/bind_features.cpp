#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>

#include "bindings/image_conversion.h"
#include "slslam/features/descriptor_matcher.h"
#include "slslam/features/orb_extractor.h"

namespace py = pybind11;

namespace slslam::bindings {
namespace {

cv::Mat WrapDescriptors(const py::array& array) {
  if (array.ndim() != 2) throw py::value_error("descriptors must be a 2-D (N x D) array");
  if (py::isinstance<py::array_t<uint8_t, py::array::c_style>>(array) &&
      (array.flags() & py::array::c_style)) {
    return cv::Mat(static_cast<int>(array.shape(0)), static_cast<int>(array.shape(1)), CV_8U,
                   const_cast<void*>(array.data()));
  }
  if (py::isinstance<py::array_t<float, py::array::c_style>>(array) &&
      (array.flags() & py::array::c_style)) {
    return cv::Mat(static_cast<int>(array.shape(0)), static_cast<int>(array.shape(1)), CV_32F,
                   const_cast<void*>(array.data()));
  }
  throw py::value_error("descriptors must be C-contiguous uint8 (binary) or float32 arrays");
}

}  // namespace

void BindFeatures(py::module_& m) {
  py::class_<OrbOptions>(m, "OrbOptions", "ORB extractor options (OpenCV ORB).")
      .def(py::init<>())
      .def_readwrite("max_features", &OrbOptions::max_features)
      .def_readwrite("scale_factor", &OrbOptions::scale_factor)
      .def_readwrite("num_levels", &OrbOptions::num_levels)
      .def_readwrite("fast_threshold", &OrbOptions::fast_threshold)
      .def_readwrite("edge_threshold", &OrbOptions::edge_threshold)
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
      "match_descriptors",
      [](const py::array& query, const py::array& train, const MatchOptions& options) {
        const cv::Mat q = WrapDescriptors(query), t = WrapDescriptors(train);
        py::gil_scoped_release release;
        return MatchDescriptors(q, t, options);
      },
      py::arg("query"), py::arg("train"), py::arg("options") = MatchOptions{},
      "Mutual nearest-neighbour + ratio matching; returns (query index, train index) pairs N x 2.");
}

}  // namespace slslam::bindings
