// slslam._core.register_clouds: LiDAR scan registration (PCL; only when built with
// SLSLAM_WITH_PCL).
#include <string>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "slslam/lidar/point_cloud_io.h"
#include "slslam/lidar/registration.h"

namespace py = pybind11;

namespace slslam::bindings {
namespace {

using lidar::Method;
using lidar::PointMatrix;
using lidar::RegistrationOptions;
using lidar::RegistrationResult;

// Copies a float32 (N, 3|4) array into a PointMatrix, with a ValueError naming `name` otherwise.
PointMatrix ToPoints(const py::array& array, const char* name) {
  if (array.ndim() != 2 || (array.shape(1) != 3 && array.shape(1) != 4)) {
    std::string shape = "(";
    for (py::ssize_t k = 0; k < array.ndim(); ++k) {
      shape += (k ? ", " : "") + std::to_string(array.shape(k));
    }
    throw py::value_error(std::string(name) + ": expected a float32 array of shape (N, 3) or " +
                          "(N, 4) (x, y, z[, intensity]), got shape " + shape + ")");
  }
  const auto points = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!points) throw py::value_error(std::string(name) + ": not convertible to float32");
  PointMatrix out(points.shape(0), points.shape(1));
  std::copy(points.data(), points.data() + points.size(), out.data());
  lidar::CheckPoints(out, name);  // NaN / too few points: std::invalid_argument -> ValueError
  return out;
}

}  // namespace

void BindLidarSlam(py::module_& m);  // bind_lidar_slam.cpp

void BindLidar(py::module_& m) {
  BindLidarSlam(m);
  py::enum_<Method>(m, "RegistrationMethod", "LiDAR registration method.")
      .value("FPFH_SAC_IA_ICP", Method::kFpfhSacIaIcp)
      .value("NDT", Method::kNdt)
      .value("PFH_SAC_IA_ICP", Method::kPfhSacIaIcp)
      .value("ICP", Method::kIcp);

  py::class_<RegistrationOptions> options(m, "RegistrationOptions",
                                          "Parameters of register_clouds (units: m, counts).");
  options.def(py::init<>()).def("check", &RegistrationOptions::Check);
#define SLSLAM_FIELD(name) options.def_readwrite(#name, &RegistrationOptions::name)
  SLSLAM_FIELD(min_range_m);
  SLSLAM_FIELD(max_range_m);
  SLSLAM_FIELD(fine_voxel_m);
  SLSLAM_FIELD(coarse_voxel_m);
  SLSLAM_FIELD(outlier_k);
  SLSLAM_FIELD(outlier_std_mul);
  SLSLAM_FIELD(normal_k);
  SLSLAM_FIELD(feature_radius_m);
  SLSLAM_FIELD(sac_ia_iterations);
  SLSLAM_FIELD(sac_ia_source_keypoints);
  SLSLAM_FIELD(sac_ia_samples);
  SLSLAM_FIELD(sac_ia_randomness);
  SLSLAM_FIELD(sac_ia_min_sample_m);
  SLSLAM_FIELD(sac_ia_max_corr_m);
  SLSLAM_FIELD(sac_ia_edge_similarity);
  SLSLAM_FIELD(sac_ia_confidence);
  SLSLAM_FIELD(sac_ia_try_identity);
  SLSLAM_FIELD(icp_source_points_coarse);
  SLSLAM_FIELD(icp_source_points_fine);
  SLSLAM_FIELD(point_to_plane);
  SLSLAM_FIELD(icp_iterations_coarse);
  SLSLAM_FIELD(icp_iterations_fine);
  SLSLAM_FIELD(icp_max_corr_coarse_m);
  SLSLAM_FIELD(icp_max_corr_fine_m);
  SLSLAM_FIELD(icp_transformation_epsilon);
  SLSLAM_FIELD(icp_fitness_epsilon);
  SLSLAM_FIELD(icp_reject_one_to_one);
  SLSLAM_FIELD(ndt_resolution_m);
  SLSLAM_FIELD(ndt_step_m);
  SLSLAM_FIELD(ndt_iterations);
  SLSLAM_FIELD(num_threads);
#undef SLSLAM_FIELD

  py::class_<RegistrationResult> result(m, "RegistrationResult",
                                        "T_target_source, quality and per-stage times [ms].");
#define SLSLAM_FIELD(name) result.def_readonly(#name, &RegistrationResult::name)
  result.def_property_readonly(
      "transform", [](const RegistrationResult& r) { return r.target_from_source.ToMatrix4(); },
      "4x4 T_target_source (target_from_source): maps source points into the target frame.");
  SLSLAM_FIELD(fitness);
  SLSLAM_FIELD(inlier_rmse);
  SLSLAM_FIELD(iterations);
  SLSLAM_FIELD(converged);
  SLSLAM_FIELD(source_points);
  SLSLAM_FIELD(source_keypoints);
  SLSLAM_FIELD(target_points);
  SLSLAM_FIELD(target_keypoints);
  SLSLAM_FIELD(preprocess_ms);
  SLSLAM_FIELD(features_ms);
  SLSLAM_FIELD(coarse_ms);
  SLSLAM_FIELD(fine_ms);
  SLSLAM_FIELD(total_ms);
#undef SLSLAM_FIELD

  m.def(
      "register_clouds",
      [](const py::array& source, const py::array& target, const RegistrationOptions& options,
         Method method) {
        const PointMatrix src = ToPoints(source, "source");
        const PointMatrix tgt = ToPoints(target, "target");
        py::gil_scoped_release release;
        return lidar::RegisterClouds(src, tgt, options, method);
      },
      py::arg("source"), py::arg("target"), py::arg("options") = RegistrationOptions(),
      py::arg("method") = Method::kFpfhSacIaIcp,
      "Register source onto target (float32 (N, 3|4) arrays [m]). Returns a RegistrationResult "
      "whose transform (4x4) is T_target_source: it maps source points into the target frame.");
  m.def(
      "read_point_cloud",
      [](const std::string& path) {
        PointMatrix points;
        {
          py::gil_scoped_release release;
          points = lidar::ReadPointCloud(path);
        }
        return points;
      },
      py::arg("path"),
      "Read a KITTI .bin, PCD or PLY point cloud (by extension) as float32 (N, 4): x, y, z "
      "[m], intensity (0 when the file has none). Raises ValueError naming the file.");
}

}  // namespace slslam::bindings
