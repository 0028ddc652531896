// The sparse map (SL-SLAM paper): keyframes, map points, map lines, their observations, the
// covisibility graph and the spanning tree. One mutex guards the whole map: tracking reads under
// it, local mapping writes under it (coarse, but simple to reason about; the expensive parts of
// local mapping run on copies outside the lock).
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "slslam/core/rigid3.h"
#include "slslam/core/thread_annotations.h"
#include "slslam/core/time.h"
#include "slslam/features/stereo_frame.h"
#include "slslam/geometry/plucker_line.h"
#include "slslam/inertial/imu_preintegration.h"
#include "slslam/inertial/inertial_state.h"
#include "slslam/place/vocabulary.h"

namespace slslam {

struct MapPoint {
  int id = -1;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< world frame [m]
  cv::Mat descriptor;                                  ///< one row, from the first observation
  std::map<int, int> observations;                     ///< keyframe id -> keypoint index
  int visible = 0;  ///< frames in whose view the point projected [-]
  int found = 0;    ///< frames that matched it [-]
  int first_keyframe = -1;
  bool bad = false;
  /// float patch of the creating keyframe's left image centred on the point's keypoint
  /// (TrackerOptions::track_refine_window_px; empty otherwise, and not saved in map files)
  cv::Mat patch;
  double patch_depth_m = 0.0;  ///< the point's depth in that keyframe [m]
};

struct MapLine {
  int id = -1;
  PluckerLine line;                                 ///< world frame
  Eigen::Vector3d start = Eigen::Vector3d::Zero();  ///< display endpoints, world frame [m]
  Eigen::Vector3d end = Eigen::Vector3d::Zero();
  cv::Mat descriptor;               ///< LBD row from the first observation
  std::map<int, int> observations;  ///< keyframe id -> segment index
  /// Stereo endpoints of its segments in keyframes with the IMU's pose (world frame [m]) with
  /// their weights: the line is their weighted fit (KeyFrame::pose_from_imu; not in map files)
  std::vector<std::pair<Eigen::Vector3d, double>> stereo_support;
  int visible = 0;
  int found = 0;
  int first_keyframe = -1;
  bool bad = false;
};

// The IMU at a keyframe: the body's (IMU frame's) velocity and the biases, and the samples from
// the keyframe before it in the IMU chain (local BA's inertial factor between the two).
struct KeyFrameInertial {
  int64_t t_ns = 0;                                        ///< camera time of the keyframe [ns]
  Eigen::Vector3d v_world_body = Eigen::Vector3d::Zero();  ///< [m/s]
  ImuBias bias;
  int previous = -1;                ///< the keyframe the samples start at (-1: first of its chain)
  int refined = 0;                  ///< local BAs that estimated this state [-]
  bool camera_tracked = true;       ///< the camera tracked its frame (not INERTIAL)
  ImuBuffer samples_from_previous;  ///< IMU times (t_cam - time_offset), covering the interval
};

// What a map's IMU terms need beside the keyframes' states (set by the tracker once the IMU
// initialised in the map's world).
struct MapInertial {
  Rigid3d body_from_cam;                              ///< the left camera in the IMU frame
  Eigen::Vector3d g_world = Eigen::Vector3d::Zero();  ///< gravity in the map's world [m/s^2]
  ImuNoiseOptions noise;
  double time_offset_s = 0.0;      ///< t_cam = t_imu + time_offset_s [s]
  double max_sample_gap_s = 0.05;  ///< no interval over a larger gap between samples [s]
  /// No IMU factor over a longer interval between keyframes (ORB-SLAM3's bound: the first-order
  /// bias correction of a longer one is poor, and its preintegration says little) [s]
  double max_interval_s = 3.0;
  /// Local BA estimates gravity's direction too, pulled towards g_world with this standard
  /// deviation (the tracker's: its inertial state's uncertainty of gravity); 0: held [rad]
  double gravity_sigma_rad = 0.0;
};

struct KeyFrame {
  int id = -1;
  Rigid3d cam_from_world;  ///< world -> camera (x_c = R x_w + t)
  std::shared_ptr<const StereoFrame> frame;
  std::vector<int> point_ids;       ///< per keypoint: map point id or -1
  std::vector<int> line_ids;        ///< per segment: map line id or -1
  std::map<int, int> covisibility;  ///< other keyframe id -> shared map points
  int parent = -1;                  ///< spanning tree parent (-1: root)
  BowVector bow;                    ///< bag of words of the left keypoints (with a vocabulary)
  FeatureVector bow_features;       ///< vocabulary node -> keypoint indices (direct index)
  /// The left image as stereo matching saw it (8-bit), kept from the keyframe's making until
  /// local mapping has triangulated its new points, which sample their patches from it
  /// (TriangulationOptions::patch_window_px); released then. Empty otherwise; not in map files.
  cv::Mat left_image;
  /// The pose is the IMU's (a keyframe made while the camera did not track, in the tracker's
  /// line-aided mode, TrackerOptions::imu.weak_update_min_lines): local BA holds it and the lines
  /// it observes, since its own observations (a few lines, noise points) leave them
  /// undetermined. Not in map files.
  bool pose_from_imu = false;
  /// The IMU's state at the keyframe (a map with an IMU, after its initialisation): local BA
  /// estimates velocity and biases with the poses. Not in map files.
  std::optional<KeyFrameInertial> inertial;
  bool bad = false;

  Eigen::Vector3d Center() const { return cam_from_world.Center(); }  ///< in the world [m]
};

// Gives a keyframe a new pose (a correction of its world around it): its IMU velocity, a vector of
// the world, turns with it.
inline void MoveKeyFrame(KeyFrame* kf, const Rigid3d& cam_from_world) {
  if (kf->inertial) {
    kf->inertial->v_world_body = cam_from_world.rotation.transpose() * kf->cam_from_world.rotation *
                                 kf->inertial->v_world_body;
  }
  kf->cam_from_world = cam_from_world;
}

// Id counters shared by the maps of one atlas, so that keyframe, point and line ids are unique
// across maps and a merge moves entries from one map into another without renumbering them.
struct MapIds {
  int next_keyframe = 0;
  int next_point = 0;
  int next_line = 0;
};

// A keyframe removed by culling, kept as its pose relative to its spanning-tree parent at the time
// (ORB-SLAM's Tcp), so that frames tracked against it still get a pose from the final map.
struct RetiredKeyFrame {
  int parent = -1;
  Rigid3d kf_from_parent;  ///< parent camera -> this keyframe's camera
};

class Map {
 public:
  // `ids` may be shared with other maps of an atlas; null: the map counts on its own.
  explicit Map(std::shared_ptr<MapIds> ids = nullptr)
      : ids_(ids ? std::move(ids) : std::make_shared<MapIds>()) {}

  // The lock of the whole map; the analysis (thread_annotations.h) knows it as mutex_.
  Mutex& mutex() const SLSLAM_RETURN_CAPABILITY(mutex_) { return mutex_; }

  // All below require the caller to hold mutex() (checked by clang's -Wthread-safety).
  std::shared_ptr<KeyFrame> AddKeyFrame(const Rigid3d& cam_from_world,
                                        std::shared_ptr<const StereoFrame> frame)
      SLSLAM_REQUIRES(mutex_);
  std::shared_ptr<MapPoint> AddPoint(const Eigen::Vector3d& position, const cv::Mat& descriptor,
                                     int keyframe_id) SLSLAM_REQUIRES(mutex_);
  std::shared_ptr<MapLine> AddLine(const PluckerLine& line, const Eigen::Vector3d& start,
                                   const Eigen::Vector3d& end, const cv::Mat& descriptor,
                                   int keyframe_id) SLSLAM_REQUIRES(mutex_);
  void AddPointObservation(int point_id, int keyframe_id, int keypoint) SLSLAM_REQUIRES(mutex_);
  void AddLineObservation(int line_id, int keyframe_id, int segment) SLSLAM_REQUIRES(mutex_);
  // Recomputes the covisibility weights of a keyframe (and its neighbours' back links) and, for a
  // keyframe without parent, links it to its strongest neighbour in the spanning tree.
  void UpdateConnections(int keyframe_id) SLSLAM_REQUIRES(mutex_);
  void ErasePoint(int point_id) SLSLAM_REQUIRES(mutex_);
  void EraseLine(int line_id) SLSLAM_REQUIRES(mutex_);
  // Marks a keyframe bad, removes its observations and reparents its children to its parent.
  void EraseKeyFrame(int keyframe_id) SLSLAM_REQUIRES(mutex_);

  std::shared_ptr<KeyFrame> keyframe(int id) const SLSLAM_REQUIRES(mutex_);
  std::shared_ptr<MapPoint> point(int id) const SLSLAM_REQUIRES(mutex_);
  // The points of ascending ids (nullptr where there is none), by one walk along the ordered
  // container instead of a tree search each: valid while the lock is held.
  std::vector<MapPoint*> PointsOf(const std::vector<int>& ascending_ids) const
      SLSLAM_REQUIRES(mutex_);
  std::shared_ptr<MapLine> line(int id) const SLSLAM_REQUIRES(mutex_);
  const std::map<int, std::shared_ptr<KeyFrame>>& keyframes() const SLSLAM_REQUIRES(mutex_) {
    return keyframes_;
  }
  const std::map<int, std::shared_ptr<MapPoint>>& points() const SLSLAM_REQUIRES(mutex_) {
    return points_;
  }
  const std::map<int, std::shared_ptr<MapLine>>& lines() const SLSLAM_REQUIRES(mutex_) {
    return lines_;
  }
  // Keyframes sharing the most map points with `id`, strongest first (at most n).
  std::vector<int> BestCovisible(int id, int n) const SLSLAM_REQUIRES(mutex_);

  // Pose of a keyframe, live or culled (through the chain of retired parents); false when the
  // id is unknown to this map.
  bool KeyFramePose(int id, Rigid3d* cam_from_world) const SLSLAM_REQUIRES(mutex_);
  const std::map<int, RetiredKeyFrame>& retired() const SLSLAM_REQUIRES(mutex_) { return retired_; }

  // Restoring a saved map, or moving entries in from another map of the atlas: entries keep their
  // ids (which must be unused here); the shared counters move past them.
  void RestoreKeyFrame(std::shared_ptr<KeyFrame> keyframe) SLSLAM_REQUIRES(mutex_);
  void RestorePoint(std::shared_ptr<MapPoint> point) SLSLAM_REQUIRES(mutex_);
  void RestoreLine(std::shared_ptr<MapLine> line) SLSLAM_REQUIRES(mutex_);
  void RestoreRetired(int id, const RetiredKeyFrame& retired) SLSLAM_REQUIRES(mutex_);
  const MapIds& ids() const { return *ids_; }
  const std::shared_ptr<MapIds>& shared_ids() const { return ids_; }
  // Moves every keyframe, point, line and retired record of `other` into this map (ids are unique
  // across an atlas); `other` is left empty. Poses are not changed: transform `other` first.
  void Absorb(Map* other) SLSLAM_REQUIRES(mutex_, other->mutex_);

  // Bumped whenever keyframe poses change outside local mapping's window (loop correction,
  // merge): a tracker holding a pose relative to the old map re-reads its reference keyframe.
  int correction_epoch() const SLSLAM_REQUIRES(mutex_) { return correction_epoch_; }
  void BumpCorrectionEpoch() SLSLAM_REQUIRES(mutex_) { ++correction_epoch_; }

  // Gravity's direction in the map's world (unit), once the IMU initialised in it; empty
  // without. Loop correction then moves the keyframes in yaw and position only.
  const std::optional<Eigen::Vector3d>& gravity_direction() const SLSLAM_REQUIRES(mutex_) {
    return gravity_direction_;
  }
  void set_gravity_direction(const Eigen::Vector3d& g_world) SLSLAM_REQUIRES(mutex_) {
    if (g_world.allFinite() && g_world.norm() > 0.0) gravity_direction_ = g_world.normalized();
  }
  // The IMU terms' settings (empty: a map without IMU factors).
  const std::optional<MapInertial>& inertial() const SLSLAM_REQUIRES(mutex_) { return inertial_; }
  void set_inertial(const MapInertial& inertial) SLSLAM_REQUIRES(mutex_) { inertial_ = inertial; }

 private:
  mutable Mutex mutex_;
  std::shared_ptr<MapIds> ids_;
  std::map<int, std::shared_ptr<KeyFrame>> keyframes_ SLSLAM_GUARDED_BY(mutex_);
  std::map<int, std::shared_ptr<MapPoint>> points_ SLSLAM_GUARDED_BY(mutex_);
  std::map<int, std::shared_ptr<MapLine>> lines_ SLSLAM_GUARDED_BY(mutex_);
  std::map<int, RetiredKeyFrame> retired_ SLSLAM_GUARDED_BY(mutex_);
  int correction_epoch_ SLSLAM_GUARDED_BY(mutex_) = 0;
  std::optional<Eigen::Vector3d> gravity_direction_ SLSLAM_GUARDED_BY(mutex_);
  std::optional<MapInertial> inertial_ SLSLAM_GUARDED_BY(mutex_);
};

}  // namespace slslam
