#include "slslam/lidar/scan_context.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "slslam/core/check.h"

namespace slslam::lidar {

void ScanContextOptions::Check() const {
  SLSLAM_CHECK(rings >= 2 && rings <= 200, "ScanContextOptions.rings must be in [2, 200], got ",
               rings);
  SLSLAM_CHECK(sectors >= 4 && sectors <= 720,
               "ScanContextOptions.sectors must be in [4, 720], got ", sectors);
  SLSLAM_CHECK(max_radius_m > 0, "ScanContextOptions.max_radius_m must be > 0 m");
  SLSLAM_CHECK(candidates >= 1, "ScanContextOptions.candidates must be >= 1");
  SLSLAM_CHECK(exclude_recent >= 0, "ScanContextOptions.exclude_recent must be >= 0");
  SLSLAM_CHECK(max_distance > 0 && max_distance <= 1,
               "ScanContextOptions.max_distance must be in (0, 1], got ", max_distance);
}

ScanContextMatrix MakeScanContext(const std::vector<Eigen::Vector3d>& points_sensor,
                                  const ScanContextOptions& options) {
  options.Check();
  ScanContextMatrix context = ScanContextMatrix::Zero(options.rings, options.sectors);
  for (const Eigen::Vector3d& p : points_sensor) {
    const double r = std::hypot(p.x(), p.y());
    if (r >= options.max_radius_m || r < 1e-6) continue;
    double azimuth = std::atan2(p.y(), p.x());
    if (azimuth < 0) azimuth += 2 * M_PI;
    const int ring =
        std::min(static_cast<int>(r / options.max_radius_m * options.rings), options.rings - 1);
    const int sector =
        std::min(static_cast<int>(azimuth / (2 * M_PI) * options.sectors), options.sectors - 1);
    const float height = static_cast<float>(std::max(p.z() + options.height_offset_m, 0.0));
    context(ring, sector) = std::max(context(ring, sector), height);
  }
  return context;
}

Eigen::VectorXf RingKey(const ScanContextMatrix& context) { return context.rowwise().mean(); }

ScanContextMatch CompareScanContexts(const ScanContextMatrix& query,
                                     const ScanContextMatrix& candidate) {
  SLSLAM_CHECK(query.rows() == candidate.rows() && query.cols() == candidate.cols(),
               "Scan Context sizes differ: ", query.rows(), "x", query.cols(), " vs ",
               candidate.rows(), "x", candidate.cols());
  const int sectors = static_cast<int>(query.cols());
  const Eigen::RowVectorXf q_norm = query.colwise().norm();
  const Eigen::RowVectorXf c_norm = candidate.colwise().norm();
  ScanContextMatch best;
  for (int shift = 0; shift < sectors; ++shift) {
    // Column j of the query is compared with column (j + shift) of the candidate.
    double sum = 0.0;
    int used = 0;
    for (int j = 0; j < sectors; ++j) {
      const int k = (j + shift) % sectors;
      if (q_norm(j) <= 0 || c_norm(k) <= 0) continue;
      sum += 1.0 - query.col(j).dot(candidate.col(k)) / (q_norm(j) * c_norm(k));
      ++used;
    }
    if (used == 0) continue;
    const double distance = sum / used;
    if (distance < best.distance) {
      best.distance = distance;
      best.shift = shift;
    }
  }
  // Sector j of the query looks where sector j + shift of the candidate looks: the query sensor
  // is turned by +shift sectors in the candidate's frame.
  best.yaw_rad = 2 * M_PI * best.shift / sectors;
  if (best.yaw_rad > M_PI) best.yaw_rad -= 2 * M_PI;
  return best;
}

ScanContextDatabase::ScanContextDatabase(const ScanContextOptions& options) : options_(options) {
  options_.Check();
}

int ScanContextDatabase::Add(const std::vector<Eigen::Vector3d>& points_sensor) {
  contexts_.push_back(MakeScanContext(points_sensor, options_));
  ring_keys_.push_back(RingKey(contexts_.back()));
  return size() - 1;
}

ScanContextMatch ScanContextDatabase::Query(int index) const {
  SLSLAM_CHECK(index >= 0 && index < size(), "Scan Context query index ", index,
               " out of range [0, ", size(), ")");
  ScanContextMatch none;
  const int searchable = index - options_.exclude_recent;
  if (searchable <= 0) return none;
  // Exact nearest ring keys by brute force: a few thousand 20-float keys cost well under a
  // millisecond, and give the candidates a kd-tree would (Kim & Kim rebuild theirs periodically).
  std::vector<std::pair<float, int>> by_key;
  by_key.reserve(searchable);
  for (int k = 0; k < searchable; ++k) {
    by_key.emplace_back((ring_keys_[k] - ring_keys_[index]).squaredNorm(), k);
  }
  const int n = std::min<int>(options_.candidates, by_key.size());
  std::partial_sort(by_key.begin(), by_key.begin() + n, by_key.end());
  ScanContextMatch best;
  for (int c = 0; c < n; ++c) {
    ScanContextMatch m = CompareScanContexts(contexts_[index], contexts_[by_key[c].second]);
    if (m.distance < best.distance) {
      best = m;
      best.index = by_key[c].second;
    }
  }
  return best.distance < options_.max_distance ? best : none;
}

}  // namespace slslam::lidar
