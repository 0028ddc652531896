// slslam._core LiDAR(-inertial) SLAM: odometry (deskew, scan-to-map, IMU smoothing), Scan
// Context loop candidates and the keyframe pose graph (lidar/keyframe_pose_graph.h). Only built
// with SLSLAM_WITH_PCL (the module lives in slslam_lidar).
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "slslam/lidar/keyframe_pose_graph.h"
#include "slslam/lidar/lidar_odometry.h"
#include "slslam/lidar/scan_context.h"

namespace py = pybind11;

namespace slslam::bindings {
namespace {

using namespace slslam::lidar;
using Points3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

std::vector<Eigen::Vector3d> ToVectors(const Points3& points) {
  std::vector<Eigen::Vector3d> out(points.rows());
  for (Eigen::Index i = 0; i < points.rows(); ++i) out[i] = points.row(i).transpose();
  return out;
}

Points3 ToArray(const std::vector<Eigen::Vector3d>& points) {
  Points3 out(points.size(), 3);
  for (size_t i = 0; i < points.size(); ++i) out.row(i) = points[i].transpose();
  return out;
}

}  // namespace

void BindLidarSlam(py::module_& m) {
#define SLSLAM_FIELD(cls, name) .def_readwrite(#name, &cls::name)
  py::class_<ImuNoiseOptions>(m, "ImuNoiseOptions", "Continuous-time IMU noise (Kalibr units).")
      .def(py::init<>())
      .def("check", &ImuNoiseOptions::Check) SLSLAM_FIELD(ImuNoiseOptions, gyro_noise_density)
          SLSLAM_FIELD(ImuNoiseOptions, acc_noise_density)
              SLSLAM_FIELD(ImuNoiseOptions, gyro_random_walk)
                  SLSLAM_FIELD(ImuNoiseOptions, acc_random_walk)
                      SLSLAM_FIELD(ImuNoiseOptions, gravity_mps2);
  py::class_<VoxelMapOptions>(m, "VoxelMapOptions", "Local map of LiDAR odometry.")
      .def(py::init<>())
      .def("check", &VoxelMapOptions::Check) SLSLAM_FIELD(VoxelMapOptions, voxel_m)
          SLSLAM_FIELD(VoxelMapOptions, max_points_per_voxel)
              SLSLAM_FIELD(VoxelMapOptions, min_point_spacing_m)
                  SLSLAM_FIELD(VoxelMapOptions, max_distance_m);
  py::class_<ScanMatchOptions>(m, "ScanMatchOptions", "Scan-to-map point-to-plane registration.")
      .def(py::init<>())
      .def("check", &ScanMatchOptions::Check) SLSLAM_FIELD(ScanMatchOptions, point_to_plane)
          SLSLAM_FIELD(ScanMatchOptions, max_iterations)
              SLSLAM_FIELD(ScanMatchOptions, max_correspondence_m)
                  SLSLAM_FIELD(ScanMatchOptions, plane_neighbours)
                      SLSLAM_FIELD(ScanMatchOptions, plane_max_thickness_m)
                          SLSLAM_FIELD(ScanMatchOptions, robust_scale_m)
                              SLSLAM_FIELD(ScanMatchOptions, convergence_translation_m)
                                  SLSLAM_FIELD(ScanMatchOptions, convergence_rotation_rad)
                                      SLSLAM_FIELD(ScanMatchOptions, prior_translation_sigma_m)
                                          SLSLAM_FIELD(ScanMatchOptions, prior_rotation_sigma_rad)
                                              SLSLAM_FIELD(ScanMatchOptions, inlier_m)
                                                  SLSLAM_FIELD(ScanMatchOptions, num_threads);
  py::class_<LioSmootherOptions>(m, "LioSmootherOptions", "Fixed-lag LiDAR-inertial smoother.")
      .def(py::init<>())
      .def("check", &LioSmootherOptions::Check) SLSLAM_FIELD(LioSmootherOptions, window)
          SLSLAM_FIELD(LioSmootherOptions, max_iterations)
              SLSLAM_FIELD(LioSmootherOptions, initial_velocity_sigma_mps)
                  SLSLAM_FIELD(LioSmootherOptions, initial_gyro_bias_sigma)
                      SLSLAM_FIELD(LioSmootherOptions, initial_acc_bias_sigma)
                          SLSLAM_FIELD(LioSmootherOptions, initial_tilt_sigma_rad);
  py::class_<LidarOdometryOptions>(m, "LidarOdometryOptions",
                                   "LiDAR(-inertial) odometry; nested option groups by name.")
      .def(py::init<>())
      .def("check", &LidarOdometryOptions::Check) SLSLAM_FIELD(LidarOdometryOptions, min_range_m)
          SLSLAM_FIELD(LidarOdometryOptions, max_range_m)
              SLSLAM_FIELD(LidarOdometryOptions, source_voxel_m)
                  SLSLAM_FIELD(LidarOdometryOptions, map_voxel_m)
                      SLSLAM_FIELD(LidarOdometryOptions, scan_period_s)
                          SLSLAM_FIELD(LidarOdometryOptions, deskew)
                              SLSLAM_FIELD(LidarOdometryOptions, use_imu)
                                  SLSLAM_FIELD(LidarOdometryOptions, scan_information_scale)
                                      SLSLAM_FIELD(LidarOdometryOptions, gravity_window_s)
                                          SLSLAM_FIELD(LidarOdometryOptions, map)
                                              SLSLAM_FIELD(LidarOdometryOptions, match)
                                                  SLSLAM_FIELD(LidarOdometryOptions, smoother)
                                                      SLSLAM_FIELD(LidarOdometryOptions, imu)
      .def_property(
          "T_body_sensor",
          [](const LidarOdometryOptions& o) { return o.body_from_sensor.ToMatrix4(); },
          [](LidarOdometryOptions& o, const Eigen::Matrix4d& T) {
            o.body_from_sensor = Rigid3d::FromMatrix4(T);
          },
          "4x4 pose of the LiDAR in the IMU (body) frame (body_from_sensor).");
  py::class_<OdometryResult>(m, "OdometryResult", "One sweep's pose, state, quality and timing.")
      .def_readonly("t_ns", &OdometryResult::t_ns)
      .def_property_readonly(
          "T_world_sensor", [](const OdometryResult& r) { return r.world_from_sensor.ToMatrix4(); },
          "4x4 pose of the LiDAR in the world at the sweep start.")
      .def_property_readonly(
          "T_world_body", [](const OdometryResult& r) { return r.world_from_body.ToMatrix4(); },
          "4x4 pose of the IMU (body) in the world at the sweep start.")
      .def_readonly("velocity_world", &OdometryResult::velocity_world)
      .def_readonly("gyro_bias", &OdometryResult::gyro_bias)
      .def_readonly("acc_bias", &OdometryResult::acc_bias)
      .def_readonly("matched", &OdometryResult::matched)
      .def_readonly("source_points", &OdometryResult::source_points)
      .def_readonly("correspondences", &OdometryResult::correspondences)
      .def_readonly("fitness", &OdometryResult::fitness)
      .def_readonly("inlier_rmse_m", &OdometryResult::inlier_rmse_m)
      .def_readonly("degeneracy", &OdometryResult::degeneracy)
      .def_readonly("map_points", &OdometryResult::map_points)
      .def_readonly("deskew_ms", &OdometryResult::deskew_ms)
      .def_readonly("match_ms", &OdometryResult::match_ms)
      .def_readonly("smoother_ms", &OdometryResult::smoother_ms)
      .def_readonly("map_ms", &OdometryResult::map_ms)
      .def_readonly("total_ms", &OdometryResult::total_ms);
  py::class_<LidarOdometry>(m, "LidarOdometry", "LiDAR(-inertial) odometry, one sweep at a time.")
      .def(py::init<const LidarOdometryOptions&>(), py::arg("options") = LidarOdometryOptions())
      .def(
          "add_imu",
          [](LidarOdometry& self, const std::vector<int64_t>& t_ns,
             const Eigen::Matrix<double, Eigen::Dynamic, 3>& gyro,
             const Eigen::Matrix<double, Eigen::Dynamic, 3>& acc) { self.AddImu(t_ns, gyro, acc); },
          py::arg("t_ns"), py::arg("gyro"), py::arg("acc"),
          "Append IMU samples: t_ns (N,) int64 increasing, gyro (N, 3) [rad/s], acc (N, 3) "
          "[m/s^2], body frame.")
      .def(
          "process_scan",
          [](LidarOdometry& self, int64_t t_ns, const PointMatrix& points,
             const std::vector<double>& point_time_s) {
            py::gil_scoped_release release;
            return self.ProcessScan(t_ns, points, point_time_s);
          },
          py::arg("t_ns"), py::arg("points"), py::arg("point_time_s") = std::vector<double>(),
          "One sweep: points float32 (N, 3|4) in the sensor frame, per-point time after t_ns "
          "[s] (empty: no deskewing). Returns an OdometryResult.")
      .def(
          "last_scan", [](const LidarOdometry& self) { return ToArray(self.last_scan()); },
          "The last sweep deskewed to its start, voxelised, sensor frame (N, 3) [m].")
      .def(
          "map_points", [](const LidarOdometry& self) { return ToArray(self.MapPoints()); },
          "Points of the local map (N, 3), world frame [m].");

  py::class_<ScanContextOptions>(m, "ScanContextOptions", "Scan Context descriptor and search.")
      .def(py::init<>())
      .def("check", &ScanContextOptions::Check) SLSLAM_FIELD(ScanContextOptions, rings)
          SLSLAM_FIELD(ScanContextOptions, sectors) SLSLAM_FIELD(ScanContextOptions, max_radius_m)
              SLSLAM_FIELD(ScanContextOptions, height_offset_m)
                  SLSLAM_FIELD(ScanContextOptions, candidates)
                      SLSLAM_FIELD(ScanContextOptions, exclude_recent)
                          SLSLAM_FIELD(ScanContextOptions, max_distance);
  py::class_<ScanContextMatch>(m, "ScanContextMatch", "Best loop candidate of a query.")
      .def_readonly("index", &ScanContextMatch::index)
      .def_readonly("distance", &ScanContextMatch::distance)
      .def_readonly("shift", &ScanContextMatch::shift)
      .def_readonly("yaw_rad", &ScanContextMatch::yaw_rad);
  py::class_<ScanContextDatabase>(m, "ScanContextDatabase", "Scan Context keyframe database.")
      .def(py::init<const ScanContextOptions&>(), py::arg("options") = ScanContextOptions())
      .def(
          "add",
          [](ScanContextDatabase& self, const Points3& points) {
            return self.Add(ToVectors(points));
          },
          py::arg("points_sensor"), "Add a keyframe's points (N, 3), sensor frame; its index.")
      .def("query", &ScanContextDatabase::Query, py::arg("index"),
           "Best older keyframe for keyframe `index` (index -1: none below max_distance).")
      .def("context", &ScanContextDatabase::context, py::arg("index"))
      .def("__len__", &ScanContextDatabase::size);

  py::class_<LidarPoseGraphOptions>(m, "LidarPoseGraphOptions", "Keyframe pose graph solver.")
      .def(py::init<>()) SLSLAM_FIELD(LidarPoseGraphOptions, max_iterations)
          SLSLAM_FIELD(LidarPoseGraphOptions, loop_cauchy_scale);
#undef SLSLAM_FIELD
  m.def(
      "optimize_lidar_pose_graph",
      [](const std::vector<Eigen::Matrix4d>& T_world_keyframe, const std::vector<int>& a,
         const std::vector<int>& b, const std::vector<Eigen::Matrix4d>& T_a_b,
         const std::vector<Eigen::Matrix<double, 6, 6>>& information, const std::vector<bool>& loop,
         const LidarPoseGraphOptions& options) {
        std::vector<Rigid3d> poses, edges;
        for (const Eigen::Matrix4d& T : T_world_keyframe) poses.push_back(Rigid3d::FromMatrix4(T));
        for (const Eigen::Matrix4d& T : T_a_b) edges.push_back(Rigid3d::FromMatrix4(T));
        std::vector<Rigid3d> optimised;
        {
          py::gil_scoped_release release;
          optimised = OptimizeLidarPoseGraph(poses, a, b, edges, information, loop, options);
        }
        std::vector<Eigen::Matrix4d> out;
        for (const Rigid3d& pose : optimised) out.push_back(pose.ToMatrix4());
        return out;
      },
      py::arg("T_world_keyframe"), py::arg("a"), py::arg("b"), py::arg("T_a_b"),
      py::arg("information"), py::arg("loop"), py::arg("options") = LidarPoseGraphOptions(),
      "Optimise keyframe poses (list of 4x4) under relative-pose edges a -> b (T_a_b, 6x6 "
      "information on translation then rotation, loop flag for the Cauchy loss); the first "
      "keyframe is held. Returns the poses.");
  m.def(
      "match_scan_to_points",
      [](const Points3& source, const Points3& target, const Eigen::Matrix4d& T_target_source,
         const ScanMatchOptions& options, double voxel_m) {
        VoxelMapOptions map_options;
        map_options.voxel_m = voxel_m;
        map_options.max_points_per_voxel = 20;
        map_options.max_distance_m = 1e6;
        VoxelMap map(map_options);
        map.Add(ToVectors(target));
        ScanMatchResult r;
        {
          py::gil_scoped_release release;
          r = MatchScanToMap(ToVectors(source), map, Rigid3d::FromMatrix4(T_target_source),
                             options);
        }
        return py::make_tuple(r.world_from_sensor.ToMatrix4(), r.fitness, r.inlier_rmse_m,
                              r.information);
      },
      py::arg("source"), py::arg("target"), py::arg("T_target_source"),
      py::arg("options") = ScanMatchOptions(), py::arg("voxel_m") = 0.5,
      "Point-to-plane registration of source (N, 3) onto target (M, 3) from an initial "
      "T_target_source; returns (T_target_source, fitness, inlier_rmse_m, information 6x6).");
}

}  // namespace slslam::bindings
