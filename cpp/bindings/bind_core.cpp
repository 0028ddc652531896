#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings/image_conversion.h"
#include "slslam/core/image_io.h"
#include "slslam/core/pinhole_camera.h"
#include "slslam/core/stereo_rectifier.h"

namespace py = pybind11;

namespace slslam::bindings {

void BindCore(py::module_& m) {
  py::class_<PinholeCamera>(m, "PinholeCamera", "Ideal pinhole intrinsics in pixels.")
      .def(py::init<>())
      .def(py::init([](double fx, double fy, double cx, double cy, int width, int height) {
             PinholeCamera c{fx, fy, cx, cy, width, height};
             c.Check();
             return c;
           }),
           py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"), py::arg("width"),
           py::arg("height"))
      .def_readwrite("fx", &PinholeCamera::fx)
      .def_readwrite("fy", &PinholeCamera::fy)
      .def_readwrite("cx", &PinholeCamera::cx)
      .def_readwrite("cy", &PinholeCamera::cy)
      .def_readwrite("width", &PinholeCamera::width)
      .def_readwrite("height", &PinholeCamera::height)
      .def("check", &PinholeCamera::Check)
      .def("K", &PinholeCamera::K)
      .def("project", &PinholeCamera::Project, py::arg("point_in_cam"))
      .def("__repr__", [](const PinholeCamera& c) {
        return "PinholeCamera(fx=" + std::to_string(c.fx) + ", fy=" + std::to_string(c.fy) +
               ", cx=" + std::to_string(c.cx) + ", cy=" + std::to_string(c.cy) +
               ", width=" + std::to_string(c.width) + ", height=" + std::to_string(c.height) + ")";
      });

  py::class_<RadTanCamera>(m, "RadTanCamera", "Pinhole with radial-tangential distortion.")
      .def(py::init([](const PinholeCamera& pinhole, const std::array<double, 4>& distortion) {
             RadTanCamera c{pinhole, distortion};
             c.Check();
             return c;
           }),
           py::arg("pinhole"), py::arg("distortion"))
      .def_readonly("pinhole", &RadTanCamera::pinhole)
      .def_readonly("distortion", &RadTanCamera::distortion);

  py::class_<StereoRectifier>(m, "StereoRectifier",
                              "Undistorts and rectifies a calibrated stereo pair (OpenCV).")
      .def(py::init<const RadTanCamera&, const RadTanCamera&, const Eigen::Matrix4d&>(),
           py::arg("left"), py::arg("right"), py::arg("T_left_right"))
      .def_property_readonly("rectified_camera", &StereoRectifier::rectified_camera)
      .def_property_readonly("baseline_m", &StereoRectifier::baseline_m)
      .def_property_readonly("R_rect_left", &StereoRectifier::R_rect_left)
      .def_property_readonly("R_rectright_right", &StereoRectifier::R_rectright_right)
      .def(
          "rectify",
          [](const StereoRectifier& self, const py::array& left, const py::array& right) {
            const cv::Mat l = WrapGray(left, "left image"), r = WrapGray(right, "right image");
            std::pair<cv::Mat, cv::Mat> out;
            {
              py::gil_scoped_release release;
              out = self.Rectify(l, r);
            }
            return py::make_tuple(ToNumpy(out.first), ToNumpy(out.second));
          },
          py::arg("left"), py::arg("right"),
          "Rectify a (left, right) pair of uint8 images; returns the rectified pair.");

  m.def(
      "read_gray_image", [](const std::string& path) { return ToNumpy(ReadGrayImage(path)); },
      py::arg("path"), "Read an image file as a uint8 gray array; ValueError names the file.");
  m.def(
      "write_image",
      [](const std::string& path, const py::array& image) {
        const cv::Mat mat = WrapGray(image, "image");
        py::gil_scoped_release release;  // PNG encoding can overlap other work
        WriteImage(path, mat);
      },
      py::arg("path"), py::arg("image"), "Write a uint8 gray image (format from the extension).");
}

}  // namespace slslam::bindings
