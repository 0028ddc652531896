// slslam._core simulator kernels: image formation from per-pixel ray hits.
#include <array>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "slslam/sim/shading.h"

namespace py = pybind11;

namespace slslam::bindings {
namespace {

using sim::HeadLamp;
using sim::Material;
using sim::SensorModel;
using sim::ShadingCamera;

using FloatArray = py::array_t<float, py::array::c_style>;
using ByteArray = py::array_t<uint8_t, py::array::c_style>;

std::string ShapeString(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) s += (k ? ", " : "") + std::to_string(a.shape(k));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// An (N, 3) or (H, W, 3) C-contiguous float32 array; returns N.
std::size_t CheckVectors(const py::array& a, const char* what) {
  if ((a.ndim() != 2 && a.ndim() != 3) || a.shape(a.ndim() - 1) != 3) {
    throw py::value_error(std::string(what) + " must be an (N, 3) or (H, W, 3) array, got shape " +
                          ShapeString(a));
  }
  if (!py::isinstance<FloatArray>(a) || !(a.flags() & py::array::c_style)) {
    throw py::value_error(std::string(what) + " must be a C-contiguous float32 array, got dtype " +
                          std::string(py::str(a.dtype())));
  }
  return static_cast<std::size_t>(a.size() / 3);
}

// An (N,) or (H, W) C-contiguous uint8 array of material ids; returns N.
std::size_t CheckMaterial(const py::array& a) {
  if (a.ndim() != 1 && a.ndim() != 2) {
    throw py::value_error("material must be an (N,) or (H, W) array, got shape " + ShapeString(a));
  }
  if (!py::isinstance<ByteArray>(a) || !(a.flags() & py::array::c_style)) {
    throw py::value_error("material must be a C-contiguous uint8 array, got dtype " +
                          std::string(py::str(a.dtype())));
  }
  return static_cast<std::size_t>(a.size());
}

std::vector<Eigen::Vector3d> LampPositions(const py::array& a) {
  if (a.size() == 0) return {};
  if (a.ndim() != 2 || a.shape(1) != 3) {
    throw py::value_error("roof_lamp_positions must be a (K, 3) array, got shape " +
                          ShapeString(a));
  }
  if (a.dtype().kind() != 'f') {
    throw py::value_error("roof_lamp_positions must be float32 or float64, got dtype " +
                          std::string(py::str(a.dtype())));
  }
  const auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  std::vector<Eigen::Vector3d> out(d.shape(0));
  for (py::ssize_t k = 0; k < d.shape(0); ++k) out[k] = {d.at(k, 0), d.at(k, 1), d.at(k, 2)};
  return out;
}

// 3-vectors cross as std::array (a list, tuple or numpy array of 3 numbers): the Eigen caster of
// the pybind11 in Debian 12 (2.10) crashes with numpy 2.
using Array3 = std::array<double, 3>;
Array3 ToArray(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Vector3d ToVector(const Array3& a) { return {a[0], a[1], a[2]}; }

template <typename T>
auto Vector3Property(Eigen::Vector3d T::*member) {
  return std::make_pair([member](const T& self) { return ToArray(self.*member); },
                        [member](T& self, const Array3& a) { self.*member = ToVector(a); });
}

}  // namespace

void BindSim(py::module_& m) {
  py::enum_<Material>(m, "Material", "Surface material ids of the simulator's shading kernel.")
      .value("ROCK", Material::kRock)
      .value("COAL", Material::kCoal)
      .value("SHOTCRETE", Material::kShotcrete)
      .value("STEEL", Material::kSteel)
      .value("ROOF_MESH", Material::kRoofMesh)
      .value("FLOOR", Material::kFloor)
      .value("PIPE", Material::kPipe)
      .value("CABLE", Material::kCable)
      .value("WORKER", Material::kWorker)
      .value("CART", Material::kCart)
      .value("NONE", Material::kNone);

  py::class_<ShadingCamera>(m, "ShadingCamera",
                            "Pinhole intrinsics [px] and optical centre [m] for shading.")
      .def(py::init<>())
      .def(py::init([](double fx, double fy, double cx, double cy, const Array3& position) {
             ShadingCamera c{fx, fy, cx, cy, ToVector(position)};
             c.Check();
             return c;
           }),
           py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"),
           py::arg("position") = Array3{0.0, 0.0, 0.0})
      .def_readwrite("fx", &ShadingCamera::fx)
      .def_readwrite("fy", &ShadingCamera::fy)
      .def_readwrite("cx", &ShadingCamera::cx)
      .def_readwrite("cy", &ShadingCamera::cy)
      .def_property("position", Vector3Property(&ShadingCamera::position).first,
                    Vector3Property(&ShadingCamera::position).second, "optical centre in world [m]")
      .def("check", &ShadingCamera::Check);

  py::class_<HeadLamp>(m, "HeadLamp",
                       "Spot light: E = power * cos / d^2 inside half_angle_rad, falling smoothly "
                       "to zero at falloff_ratio * half_angle_rad.")
      .def(py::init<>())
      .def_property("position", Vector3Property(&HeadLamp::position).first,
                    Vector3Property(&HeadLamp::position).second, "in world [m]")
      .def_property("direction", Vector3Property(&HeadLamp::direction).first,
                    Vector3Property(&HeadLamp::direction).second, "unit forward axis in world")
      .def_readwrite("power", &HeadLamp::power, "intensity [irradiance units * m^2]")
      .def_readwrite("half_angle_rad", &HeadLamp::half_angle_rad, "fully lit half-angle [rad]")
      .def_readwrite("falloff_ratio", &HeadLamp::falloff_ratio, "zero at this x half-angle")
      .def("check", &HeadLamp::Check);

  py::class_<SensorModel>(m, "SensorModel",
                          "s = radiance * cos^4 * exposure (full-well fraction); DN = gain * 255 "
                          "* s + shot/read noise; out = 255 * (DN / 255)^gamma.")
      .def(py::init<>())
      .def_readwrite("exposure", &SensorModel::exposure, "radiance -> full-well fraction")
      .def_readwrite("gain", &SensorModel::gain, "analog gain [-]")
      .def_readwrite("gamma", &SensorModel::gamma, "encoding exponent (1/2.2; 1 = linear)")
      .def_readwrite("full_well_electrons", &SensorModel::full_well_electrons, "[e-]")
      .def_readwrite("read_noise_dn", &SensorModel::read_noise_dn, "read noise sigma [DN]")
      .def_readwrite("vignetting", &SensorModel::vignetting, "cos^4 falloff on/off")
      .def_readwrite("noise", &SensorModel::noise, "shot + read noise on/off")
      .def_readwrite("seed", &SensorModel::seed, "noise seed")
      .def("check", &SensorModel::Check);

  m.def(
      "shade_image",
      [](const py::array& points, const py::array& normals, const py::array& material, int height,
         int width, const ShadingCamera& camera, const HeadLamp& headlamp,
         const py::array& roof_lamp_positions, double roof_lamp_power, double light_level,
         double ambient, const SensorModel& sensor, uint64_t frame_index) {
        const std::size_t n = CheckVectors(points, "points");
        const std::size_t n_normals = CheckVectors(normals, "normals");
        const std::size_t n_material = CheckMaterial(material);
        if (height <= 0 || width <= 0) {
          throw py::value_error("height and width must be positive, got " + std::to_string(height) +
                                " x " + std::to_string(width));
        }
        const std::size_t expected = static_cast<std::size_t>(height) * width;
        if (n != expected || n_normals != expected || n_material != expected) {
          throw py::value_error(
              "points, normals and material need height * width = " + std::to_string(expected) +
              " entries, got " + std::to_string(n) + ", " + std::to_string(n_normals) + ", " +
              std::to_string(n_material));
        }
        sim::Lighting lighting;
        lighting.headlamp = headlamp;
        lighting.roof_lamp_positions = LampPositions(roof_lamp_positions);
        lighting.roof_lamp_power = roof_lamp_power;
        lighting.light_level = light_level;
        lighting.ambient = ambient;
        sim::ShadingInput input;
        input.points_world = static_cast<const float*>(points.data());
        input.normals_world = static_cast<const float*>(normals.data());
        input.material = static_cast<const uint8_t*>(material.data());
        input.count = n;
        // Explicit strides: pybind11 2.10 reads a zero item size from numpy 2 dtypes otherwise.
        py::array_t<uint8_t> image(
            {static_cast<py::ssize_t>(height), static_cast<py::ssize_t>(width)},
            {static_cast<py::ssize_t>(width), py::ssize_t{1}});
        uint8_t* out = image.mutable_data();
        {
          py::gil_scoped_release release;
          sim::ShadeImage(input, height, width, camera, lighting, sensor, frame_index, out);
        }
        return image;
      },
      py::arg("points"), py::arg("normals"), py::arg("material"), py::arg("height"),
      py::arg("width"), py::arg("camera"), py::arg("headlamp"), py::arg("roof_lamp_positions"),
      py::arg("roof_lamp_power"), py::arg("light_level"), py::arg("ambient"), py::arg("sensor"),
      py::arg("frame_index"),
      "Shade one image from per-pixel hits (row-major, N = height * width): points and normals "
      "float32 (N, 3) or (H, W, 3) in world [m], material uint8 ids (255 = no hit). Returns a "
      "uint8 (height, width) image; deterministic for a given sensor.seed and frame_index.");

  m.def(
      "relief_normals",
      [](const py::array& points, const py::array& normals, float height_m, float wavelength_m,
         const py::object& footprint_m, int octaves) {
        const std::size_t n = CheckVectors(points, "points");
        if (CheckVectors(normals, "normals") != n) {
          throw py::value_error("normals must have as many rows as points (" + std::to_string(n) +
                                ")");
        }
        const float* footprint = nullptr;
        FloatArray footprint_array;
        if (!footprint_m.is_none()) {
          footprint_array = FloatArray::ensure(footprint_m);
          if (!footprint_array || footprint_array.ndim() != 1 ||
              static_cast<std::size_t>(footprint_array.size()) != n) {
            throw py::value_error("footprint_m must be a float32 (N,) array, N = " +
                                  std::to_string(n));
          }
          footprint = footprint_array.data();
        }
        sim::ReliefOptions options;
        options.height_m = height_m;
        options.wavelength_m = wavelength_m;
        options.octaves = octaves;
        options.Check();  // (std::invalid_argument reaches Python as ValueError)
        py::array_t<float> out(
            {static_cast<py::ssize_t>(n), py::ssize_t{3}},
            {static_cast<py::ssize_t>(3 * sizeof(float)), static_cast<py::ssize_t>(sizeof(float))});
        const float* p = static_cast<const float*>(points.data());
        const float* nrm = static_cast<const float*>(normals.data());
        float* o = out.mutable_data();
        {
          py::gil_scoped_release release;
          sim::ReliefNormals(p, nrm, footprint, n, options, o);
        }
        return out;
      },
      py::arg("points"), py::arg("normals"), py::arg("height_m"), py::arg("wavelength_m"),
      py::arg("footprint_m") = py::none(), py::arg("octaves") = 3,
      "Unit normals (float32 (N, 3)) of world points (float32 (N, 3) [m]) on surfaces with unit "
      "normals once a relief h = height_m * fBm(p / wavelength_m, octaves) is added along them; "
      "footprint_m (float32 (N,), [m]) fades octaves below a few pixel footprints.");

  m.def(
      "solid_texture",
      [](const py::array& points, const py::array& material, const py::object& normals) {
        const std::size_t n = CheckVectors(points, "points");
        const std::size_t n_material = CheckMaterial(material);
        if (n_material != n) {
          throw py::value_error("material has " + std::to_string(n_material) + " entries, points " +
                                std::to_string(n));
        }
        const float* normal_data = nullptr;
        py::array normals_array;
        if (!normals.is_none()) {
          normals_array = normals.cast<py::array>();
          if (CheckVectors(normals_array, "normals") != n) {
            throw py::value_error("normals must have as many rows as points (" + std::to_string(n) +
                                  ")");
          }
          normal_data = static_cast<const float*>(normals_array.data());
        }
        py::array_t<float> albedo({static_cast<py::ssize_t>(n)},
                                  {static_cast<py::ssize_t>(sizeof(float))});
        const float* p = static_cast<const float*>(points.data());
        const uint8_t* mat = static_cast<const uint8_t*>(material.data());
        float* out = albedo.mutable_data();
        {
          py::gil_scoped_release release;
          sim::SolidTexture(p, normal_data, mat, n, out);
        }
        return albedo;
      },
      py::arg("points"), py::arg("material"), py::arg("normals") = py::none(),
      "Albedo in [0, 1] (float32, N) of world points (float32 (N, 3) [m]) with uint8 material "
      "ids; bolt plates are drawn only when normals are given.");
}

}  // namespace slslam::bindings
