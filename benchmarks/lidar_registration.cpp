// LiDAR registration benchmark (SPEC part B1, the seed's comparison table): every method on every
// real scan pair with ground truth; time is the median of N runs of the whole RegisterClouds call,
// errors are per axis (roll, pitch, yaw [deg]; x, y, z [m]) and total.
//
// Usage: slslam_lidar_benchmark [--data DIR] [--runs N] [--json PATH] [--threads N]
//   DIR defaults to ../shared/data/lidar next to the repository (SLSLAM_SHARED_DATA_DIR).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "slslam/lidar/evaluation.h"
#include "slslam/lidar/point_cloud_io.h"
#include "slslam/lidar/registration.h"

namespace lidar = slslam::lidar;

namespace {

struct Pair {
  std::string name;
  lidar::PointMatrix source, target;
  slslam::Rigid3d truth;  // target_from_source
};

std::vector<Pair> LoadPairs(const std::string& dir) {
  std::vector<Pair> pairs;
  const std::string kitti = dir + "/kitti00_scancontext/";
  if (std::filesystem::exists(kitti + "000094.bin")) {
    const auto poses = lidar::ReadKittiPoses(kitti + "poses_cam0_kitti_format.txt");
    const slslam::Rigid3d tr = lidar::ReadKittiCalibTr(kitti + "calib_Tr_velo_to_cam0_seq00.txt");
    for (auto [t, s] : {std::pair{94, 95}, std::pair{198, 199}}) {
      char name[64], src[16], tgt[16];
      std::snprintf(name, sizeof(name), "kitti00_%d->%d", s, t);
      std::snprintf(src, sizeof(src), "%06d.bin", s);
      std::snprintf(tgt, sizeof(tgt), "%06d.bin", t);
      pairs.push_back({name, lidar::ReadKittiBin(kitti + src), lidar::ReadKittiBin(kitti + tgt),
                       lidar::KittiRelativeVelo(poses.at(t), poses.at(s), tr)});
    }
  }
  const std::string gicp = dir + "/gicp_pairs/";
  if (std::filesystem::exists(gicp + "small_gicp_source.ply")) {
    pairs.push_back({"small_gicp", lidar::ReadPly(gicp + "small_gicp_source.ply"),
                     lidar::ReadPly(gicp + "small_gicp_target.ply"),
                     lidar::ReadRigid3d(gicp + "small_gicp_T_target_source.txt")});
    pairs.push_back({"fast_gicp", lidar::ReadPcd(gicp + "fast_gicp_251371071.pcd"),
                     lidar::ReadPcd(gicp + "fast_gicp_251370668.pcd"),
                     lidar::ReadRigid3d(gicp + "fast_gicp_relative.txt")});
  }
  return pairs;
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = std::string(SLSLAM_SHARED_DATA_DIR) + "/lidar";
  std::string json_path = "benchmarks/results/lidar_registration.json";
  int runs = 7;
  lidar::RegistrationOptions options;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--data")
      data = value;
    else if (key == "--runs")
      runs = std::max(1, std::atoi(value.c_str()));
    else if (key == "--json")
      json_path = value;
    else if (key == "--threads")
      options.num_threads = std::atoi(value.c_str());
    else {
      std::fprintf(stderr, "unknown argument %s\n", key.c_str());
      return 2;
    }
  }
  const std::vector<Pair> pairs = LoadPairs(data);
  if (pairs.empty()) {
    std::fprintf(stderr, "no scan pairs under %s\n", data.c_str());
    return 1;
  }
  const lidar::Method methods[] = {lidar::Method::kFpfhSacIaIcp, lidar::Method::kNdt,
                                   lidar::Method::kPfhSacIaIcp, lidar::Method::kIcp};
  std::printf("%u hardware threads, %d runs per cell (time: median of the whole call)\n",
              std::thread::hardware_concurrency(), runs);
  std::printf("%-18s %-16s %9s %7s %7s %7s %7s %8s %8s %8s %8s %6s %6s\n", "pair", "method",
              "time_ms", "roll", "pitch", "yaw", "rot_deg", "x_m", "y_m", "z_m", "trans_m", "fit",
              "iters");
  std::string json = "{\n  \"runs\": " + std::to_string(runs) + ",\n  \"results\": [\n";
  bool first = true;
  for (const Pair& pair : pairs) {
    for (lidar::Method method : methods) {
      std::vector<double> times;
      lidar::RegistrationResult result;
      for (int r = 0; r < runs; ++r) {
        result = lidar::RegisterClouds(pair.source, pair.target, options, method);
        times.push_back(result.total_ms);
      }
      std::sort(times.begin(), times.end());
      const double median = times[times.size() / 2];
      const lidar::PoseError e = lidar::ComparePoses(result.target_from_source, pair.truth);
      const std::string name = lidar::MethodName(method);
      std::printf("%-18s %-16s %9.1f %7.3f %7.3f %7.3f %7.3f %8.4f %8.4f %8.4f %8.4f %6.3f %6d\n",
                  pair.name.c_str(), name.c_str(), median, e.roll_deg, e.pitch_deg, e.yaw_deg,
                  e.rotation_deg, e.x_m, e.y_m, e.z_m, e.translation_m, result.fitness,
                  result.iterations);
      char row[1024];
      std::snprintf(row, sizeof(row),
                    "%s    {\"pair\": \"%s\", \"method\": \"%s\", \"time_ms_median\": %.3f, "
                    "\"preprocess_ms\": %.3f, \"features_ms\": %.3f, \"coarse_ms\": %.3f, "
                    "\"fine_ms\": %.3f, \"roll_deg\": %.5f, \"pitch_deg\": %.5f, \"yaw_deg\": "
                    "%.5f, \"rotation_deg\": %.5f, \"x_m\": %.5f, \"y_m\": %.5f, \"z_m\": %.5f, "
                    "\"translation_m\": %.5f, \"fitness\": %.4f, \"inlier_rmse_m\": %.4f, "
                    "\"iterations\": %d, \"converged\": %s}",
                    first ? "" : ",\n", pair.name.c_str(), name.c_str(), median,
                    result.preprocess_ms, result.features_ms, result.coarse_ms, result.fine_ms,
                    e.roll_deg, e.pitch_deg, e.yaw_deg, e.rotation_deg, e.x_m, e.y_m, e.z_m,
                    e.translation_m, result.fitness, result.inlier_rmse, result.iterations,
                    result.converged ? "true" : "false");
      json += row;
      first = false;
    }
  }
  json += "\n  ]\n}\n";
  std::ofstream(json_path) << json;
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
