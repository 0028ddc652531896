// numpy <-> cv::Mat for 8-bit gray images and descriptor tables, used by every binding file.
#pragma once

#include <cstring>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <opencv2/core.hpp>

namespace slslam::bindings {

namespace py = pybind11;

using GrayArray = py::array_t<uint8_t, py::array::c_style>;

// Wraps a 2-D uint8 array as a cv::Mat header without copying; the array must outlive the Mat.
// `what` names the argument in the error message ("left image").
inline cv::Mat WrapGray(const py::array& array, const std::string& what) {
  if (array.ndim() != 2) {
    throw py::value_error(what + " must be a 2-D (H x W) gray image, got " +
                          std::to_string(array.ndim()) + " dimensions");
  }
  if (!py::isinstance<GrayArray>(array) || !(array.flags() & py::array::c_style)) {
    throw py::value_error(what + " must be a C-contiguous uint8 array");
  }
  return cv::Mat(static_cast<int>(array.shape(0)), static_cast<int>(array.shape(1)), CV_8UC1,
                 const_cast<void*>(array.data()));
}

// Wraps an (N, D) descriptor table without copying: uint8 -> CV_8U (binary), float32 -> CV_32F.
inline cv::Mat WrapDescriptors(const py::array& array) {
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

// Copies a cv::Mat (8U or 32F, 1 channel) into a new numpy array.
inline py::array ToNumpy(const cv::Mat& mat) {
  const cv::Mat contiguous = mat.isContinuous() ? mat : mat.clone();
  if (contiguous.depth() == CV_8U) {
    py::array_t<uint8_t> out({contiguous.rows, contiguous.cols});
    std::memcpy(out.mutable_data(), contiguous.data, contiguous.total() * contiguous.elemSize());
    return out;
  }
  if (contiguous.depth() == CV_32F) {
    py::array_t<float> out({contiguous.rows, contiguous.cols});
    std::memcpy(out.mutable_data(), contiguous.data, contiguous.total() * contiguous.elemSize());
    return out;
  }
  throw py::type_error("only 8-bit and 32-bit float matrices convert to numpy");
}

}  // namespace slslam::bindings
