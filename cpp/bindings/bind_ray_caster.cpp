// slslam._core.RayCaster: Embree ray casting of triangle meshes for the simulator.
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "slslam/sim/ray_caster.h"

namespace py = pybind11;

namespace slslam::bindings {
namespace {

using sim::RayCaster;
using sim::RayHits;

// Hands a vector to numpy without copying: the array owns it through a capsule.
template <typename T>
py::array Adopt(std::vector<T>&& data, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(data));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  std::vector<py::ssize_t> strides(shape.size(), sizeof(T));
  for (int k = static_cast<int>(shape.size()) - 2; k >= 0; --k) {
    strides[k] = strides[k + 1] * shape[k + 1];
  }
  return py::array_t<T>(shape, strides, owned->data(), owner);
}

py::dict ToDict(RayHits&& hits, std::vector<py::ssize_t> shape) {
  std::vector<py::ssize_t> vector_shape = shape;
  vector_shape.push_back(3);
  py::dict out;
  out["t"] = Adopt(std::move(hits.t), shape);
  out["normal"] = Adopt(std::move(hits.normal), vector_shape);
  out["point"] = Adopt(std::move(hits.point), vector_shape);
  out["material"] = Adopt(std::move(hits.material), shape);
  return out;
}

}  // namespace

void BindRayCaster(py::module_& m) {
  py::class_<RayCaster>(m, "RayCaster",
                        "A static triangle mesh prepared for ray casting (Embree, BVH built once).")
      .def(py::init(
               [](const RayCaster::Vertices& vertices, const RayCaster::Triangles& triangles,
                  const py::array_t<uint8_t, py::array::c_style | py::array::forcecast>& material) {
                 if (material.ndim() != 1) throw py::value_error("material must be a 1-D array");
                 std::vector<uint8_t> ids(material.data(), material.data() + material.size());
                 return std::make_unique<RayCaster>(vertices, triangles, std::move(ids));
               }),
           py::arg("vertices"), py::arg("triangles"), py::arg("material"),
           "vertices float (V, 3) [m], triangles uint32 (F, 3), material uint8 (F,) ids.")
      .def_property_readonly("num_triangles", &RayCaster::num_triangles)
      .def(
          "cast",
          [](const RayCaster& self, const Eigen::Vector3f& origin,
             const RayCaster::Vertices& directions, const RayCaster* dynamic) {
            RayHits hits;
            {
              py::gil_scoped_release release;
              hits = self.Cast(origin, directions, dynamic);
            }
            return ToDict(std::move(hits), {static_cast<py::ssize_t>(directions.rows())});
          },
          py::arg("origin"), py::arg("directions"), py::arg("dynamic") = nullptr,
          "Cast rays from one origin along unit directions (N, 3). Returns a dict of numpy "
          "arrays: t (N,) [m] (inf: miss), normal (N, 3), point (N, 3), material (N,) uint8.")
      .def(
          "cast_pinhole",
          [](const RayCaster& self, const Eigen::Matrix3d& R_world_cam,
             const Eigen::Vector3d& origin, double fx, double fy, double cx, double cy, int width,
             int height, const RayCaster* dynamic) {
            RayHits hits;
            std::vector<float> depth;
            {
              py::gil_scoped_release release;
              hits = self.CastPinhole(R_world_cam, origin, fx, fy, cx, cy, width, height, dynamic,
                                      &depth);
            }
            py::dict out = ToDict(std::move(hits), {height, width});
            out["depth"] = Adopt(std::move(depth), {height, width});
            return out;
          },
          py::arg("R_world_cam"), py::arg("origin"), py::arg("fx"), py::arg("fy"), py::arg("cx"),
          py::arg("cy"), py::arg("width"), py::arg("height"), py::arg("dynamic") = nullptr,
          "One ray per pixel of a pinhole camera. Returns t, depth (H, W) [m], normal, point "
          "(H, W, 3) and material (H, W) uint8; pixel (u, v) looks along R_world_cam * "
          "normalize((u - cx) / fx, (v - cy) / fy, 1).");
}

}  // namespace slslam::bindings
