// Scan Context place descriptor (Kim & Kim, IROS 2018; the LiDAR SLAM's loop candidates): the scan
// around the sensor in a polar grid of rings x sectors holding the maximum point height per bin;
// a ring key (mean of each ring, rotation invariant) for fast candidate search; and the
// column-shift distance that also returns the yaw between two scans.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace slslam::lidar {

struct ScanContextOptions {
  int rings = 20;                ///< radial bins [-]
  int sectors = 60;              ///< azimuth bins (6 deg each) [-]
  double max_radius_m = 40.0;    ///< points farther away are ignored [m]
  double height_offset_m = 2.0;  ///< added to z so that floor points give positive heights [m]
  int candidates = 10;           ///< ring-key nearest neighbours tried per query [-]
  int exclude_recent = 100;      ///< the newest keyframes are not loop candidates [-]
  double max_distance = 0.2;     ///< accept a match below this column-cosine distance [-]
  void Check() const;
};

// rings x sectors matrix of maximum heights (0 where a bin is empty).
using ScanContextMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

ScanContextMatrix MakeScanContext(const std::vector<Eigen::Vector3d>& points_sensor,
                                  const ScanContextOptions& options);
Eigen::VectorXf RingKey(const ScanContextMatrix& context);

struct ScanContextMatch {
  int index = -1;         ///< matched keyframe (-1: none)
  double distance = 1.0;  ///< column-cosine distance at the best shift [0, 1]
  int shift = 0;          ///< sector shift of the query that aligns it to the match [-]
  double yaw_rad = 0.0;   ///< yaw of the query sensor in the match's sensor frame [rad]
};

// Distance between two contexts at the best column shift of `query` (mean cosine distance of the
// columns that are non-empty in both), with that shift and its yaw.
ScanContextMatch CompareScanContexts(const ScanContextMatrix& query,
                                     const ScanContextMatrix& candidate);

// Keyframe database: add contexts in time order, query the newest against older ones.
class ScanContextDatabase {
 public:
  explicit ScanContextDatabase(const ScanContextOptions& options = {});
  // Adds a keyframe's scan; returns its index.
  int Add(const std::vector<Eigen::Vector3d>& points_sensor);
  // Best older keyframe for keyframe `index` (ring-key candidates, then column shift), or
  // index = -1 when none is below max_distance.
  ScanContextMatch Query(int index) const;
  int size() const { return static_cast<int>(contexts_.size()); }
  const ScanContextMatrix& context(int index) const { return contexts_.at(index); }

 private:
  ScanContextOptions options_;
  std::vector<ScanContextMatrix> contexts_;
  std::vector<Eigen::VectorXf> ring_keys_;
};

}  // namespace slslam::lidar
