// The IMU in tracking: visual-inertial initialisation from the first seconds of tracked stereo
// poses, then an inertial state (pose, velocity, biases, covariance; inertial/inertial_state.h)
// carried from frame to frame by the preintegrated IMU, which predicts each frame's pose and
// gives the frame's pose optimisation a prior (the inertial factor to the previous frame,
// marginalised onto the new pose), and is conditioned on the optimised pose again. A frame the
// camera cannot track keeps the propagated pose and its growing covariance (state INERTIAL);
// the tracker is lost when the position's standard deviation passes a fraction of the distance
// driven since the last visual fix (or an absolute floor), not after a fixed time.
//
// Frames: world = the active map's world (not gravity-aligned: gravity is estimated in it);
// body = the IMU frame; cam = the rectified left camera, body_from_cam the extrinsics. Times are
// int64 ns (core/time.h) on the camera's clock; an IMU sample's time is shifted by time_offset_s
// onto it.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"
#include "slslam/core/time.h"
#include "slslam/inertial/inertial_initialization.h"
#include "slslam/inertial/inertial_state.h"
#include "slslam/optimization/pose_optimizer.h"

namespace slslam {

struct InertialOptions {
  Rigid3d body_from_cam;       ///< the left camera in the IMU frame
  double time_offset_s = 0.0;  ///< t_cam = t_imu + time_offset_s [s]
  // IMU noise (Kalibr / EuRoC sensor.yaml units).
  double gyro_noise_density = 1.6968e-4;  ///< [rad/s/sqrt(Hz)]
  double acc_noise_density = 2.0e-3;      ///< [m/s^2/sqrt(Hz)]
  double gyro_random_walk = 1.9393e-5;    ///< [rad/s^2/sqrt(Hz)]
  double acc_random_walk = 3.0e-3;        ///< [m/s^3/sqrt(Hz)]
  double gravity_mps2 = 9.81;             ///< expected magnitude of gravity [m/s^2]
  double gravity_tolerance_mps2 = 0.5;    ///< initialisation refused further off [m/s^2]
  /// Standard deviation of the accelerometer bias about zero before any motion showed it: the
  /// initialisation's prior on it, and (at most 0.1 m/s^2) its sigma in the state after. Over
  /// the initialisation's window (1 s) a bias of 0.1 m/s^2 moves the body by 5 cm, about a dim
  /// frame's pose error, and cannot be told from a tilt of gravity: a weak prior lets the fit
  /// take the poses' noise for bias. A turn-on bias the prior holds back shows as a tilt of the
  /// estimated gravity, which is the same for dead reckoning until the body turns, and the
  /// state's updates move it into the bias as the body turns (as ORB-SLAM3's first
  /// initialisation, which holds the bias at zero) [m/s^2]
  double acc_bias_prior_mps2 = 0.02;
  /// Standard deviation of the gyroscope bias in the state after an initialisation, at least:
  /// the fit's own uncertainty (rotation misfit over the window's span) when larger; its random
  /// walk is added as time goes on. A refinement is taken only when its fit is the better one
  /// and agrees; a new map's initialisation starts from the last bias with this prior. Each
  /// tracked frame corrects the state as if independent of the last, but a map seen through
  /// weak texture turns slowly with the frames tracked on it: a loose bias takes that turn for a
  /// bias and the state turns with the map (2e-3 on issue 62's relief lining: the bias
  /// 1e-3-3e-3 rad/s off, 4 degrees of heading in 22 s). EuRoC-grade gyroscopes hold their bias
  /// to about 1e-4 rad/s over a minute [rad/s]
  double gyro_bias_sigma_radps = 1e-4;
  double window_s = 3.0;           ///< tracked poses the initialisation uses, before the last [s]
  double min_window_s = 1.0;       ///< the initialisation needs poses spanning at least this [s]
  double refine_after_s = 10.0;    ///< initialisation run again this long after the first [s]
  double refine_min_path_m = 1.0;  ///< ... over a window in which the body moved this far [m]
  double max_sample_gap_s = 0.05;  ///< IMU samples further apart than this: no propagation [s]
  /// Lost when the position's standard deviation passes this fraction of the distance driven
  /// since the last frame the camera tracked ...
  double lost_sigma_fraction = 0.1;
  double lost_sigma_min_m = 0.3;  ///< ... or this, whichever is larger [m]
  double max_gap_s = 60.0;        ///< and at the latest after this long without vision [s]
  /// Past the lost bound the IMU goes on dead reckoning (until max_gap_s), and the first frame
  /// that could start a map (after the tracker's new_map_after_lost_frames) resumes the map it
  /// left instead: a keyframe at the IMU's pose, the state's pose uncertainty restarted there,
  /// unless the state's speed ran away (SpeedPlausible). The map stays one, its part after the
  /// stretch placed by dead reckoning, where a loop closure corrects it as any drift (false: a
  /// new map, as ORB-SLAM3's) [-]
  bool resume_map_after_lost = true;
  /// A frame without vision holds the body's velocity to the axis it kept while the camera
  /// tracked (a ground vehicle's non-holonomic constraint: it neither slides sideways nor lifts
  /// off; at rest and in a turn on the spot the axis turns with it) when, over at least 2 s
  /// of tracked driving, the velocity across that axis was at most this
  /// fraction of the speed (RMS); a drone or a hand-held rig moves every way and never gets it
  /// (0: never). Without it the vertical and lateral position of a blind stretch drift with the
  /// accelerometer bias's random walk (issue 62's dark relief lining: 2.9 m down and 2.0 m
  /// sideways after 20 s, 0.3 m along the path) [-]
  double nonholonomic_max_side_ratio = 0.1;
  /// ... within this standard deviation [m/s] per frame, or the RMS side speed measured while
  /// tracked when larger (the rig's vibration, a lever arm from the turning axis)
  double nonholonomic_sigma_mps = 0.05;
  /// A frame without vision whose last kRestWindowS (0.5 s) of IMU samples show the body at rest
  /// (ImuBuffer::RestStatistic, about 1 at rest, at most this) is conditioned on zero velocity
  /// (a mine robot stops and waits), unless the state disagrees beyond 99.9 % (chi-square, 3
  /// degrees of freedom): a rig gliding at constant speed looks at rest to the IMU alone
  /// (0: never) [-]
  double zero_velocity_max_statistic = 3.0;
  double zero_velocity_sigma_mps = 0.01;  ///< ... within this standard deviation [m/s]
  /// A frame the camera does not track is conditioned on the body's velocity measured by optical
  /// flow from the frame before (tracking/stereo_flow.h) when the flow keeps this many PnP
  /// inliers (0: never), unless the state disagrees beyond 99.9 %: descriptor matching finds
  /// next to nothing on the faint relief of a smooth lining where tracked corners still follow
  /// its shading, and that velocity holds the position along the path, which the axis of travel
  /// and the stops do not [-]
  int flow_min_inliers = 30;
  /// ... within at least this standard deviation per axis [m/s] (the flow's own covariance, from
  /// its reprojection residuals, when larger; its depths from stereo add error it does not see)
  double flow_sigma_mps = 0.05;
  /// A frame the camera does not track (fewer than the tracker's min_inliers) still corrects the
  /// state with its pose optimisation when it keeps this many inliers (0: never). Off: on smooth
  /// shotcrete the few matches are sensor noise and pull the state away from the truth faster
  /// than the IMU alone drifts (benchmarks/hard_cases.py) [-]
  int weak_update_min_inliers = 0;
  /// ... and when its pose optimisation (with the IMU's prior) keeps this many line inliers
  /// (0: never): the edges where a lining's wall meets the floor are real structure where points
  /// are noise; they fix the heading, the height and the lateral position, the prior the rest [-]
  int weak_update_min_lines = 0;
  /// An INERTIAL frame with too few stereo points for a map becomes such a keyframe when it has
  /// this many stereo lines (0: points only), so that the lines of a stretch without points
  /// enter the map for the frames after it [-]
  int keyframe_min_stereo_lines = 0;
  /// An INERTIAL frame with stereo points for a map (as one that starts a map) becomes a keyframe
  /// at the IMU's pose when the last keyframe is this old, so that the map goes on through a
  /// stretch the local map does not cover (0: never) [s]
  double keyframe_interval_s = 0.5;
  /// The pose optimiser's information scaled by this before it corrects the state (the
  /// observations' pixel sigmas are optimistic: matches correlate, the map has its own error) [-]
  double visual_information_scale = 0.25;
  /// Local BA also estimates the velocity and biases of the last this many keyframes of the IMU
  /// chain (KeyFrame::inertial), with the preintegrated IMU between consecutive ones as factors
  /// (optimization/inertial_factor.h); 0: a visual local BA, the IMU in tracking only [-]
  int local_ba_keyframes = 0;

  ImuNoiseOptions Noise() const;
  InertialInitOptions Init() const;
  int64_t time_offset_ns() const { return NsFromSeconds(time_offset_s); }
  void Check() const;
};

class InertialEstimator {
 public:
  explicit InertialEstimator(const InertialOptions& options);

  // One IMU sample at t_imu_ns on the IMU's clock (increasing; else std::invalid_argument).
  void AddImu(int64_t t_imu_ns, const Eigen::Vector3d& gyro_radps, const Eigen::Vector3d& acc_mps2);

  // The state propagated to camera time t_ns from the last one, without keeping it; false when
  // not initialised or the samples do not cover the interval.
  bool Predict(int64_t t_ns, InertialState* out) const;
  // The prior that prediction gives the pose optimiser at t_ns (false as Predict).
  bool PosePriorAt(int64_t t_ns, PosePrior* prior) const;

  // A pose the camera estimated at t_ns. `information` (left tangent): the pose optimiser's,
  // computed with the prior of PosePriorAt(t_ns) when `with_prior`, without it otherwise (it is
  // then fused with the prediction); zero: a pose without an uncertainty (relocalised), taken as
  // it is. Before initialisation the pose joins the initialisation window and may complete it.
  // `unobserved_world`: a unit world direction along which the images do not observe the
  // camera's position (a pose from parallel lines alone): their information along it is dropped
  // (zero: none).
  void AddVisualPose(int64_t t_ns, const Rigid3d& cam_from_world, const Matrix6d& information,
                     bool with_prior,
                     const Eigen::Vector3d& unobserved_world = Eigen::Vector3d::Zero());
  // The frame at t_ns keeps the propagated state (the camera contributed nothing). False when it
  // cannot be propagated (not initialised, samples missing): the caller then forgets the state.
  bool Propagate(int64_t t_ns);
  // The frame at t_ns (after Propagate or AddVisualPose at t_ns) with the camera's motion from
  // its frame at prev_t_ns measured apart from the map (optical flow): `cur_from_prev` of the
  // camera and its covariance (rotation R -> Exp(dtheta) R, then translation), taken as the
  // body's velocity (flow_sigma_mps, the 99.9 % gate); frames further apart than 0.2 s are not
  // (the measurement is the interval's mean velocity). False, state unchanged, when not taken.
  bool AddCameraMotion(int64_t prev_t_ns, int64_t t_ns, const Rigid3d& cur_from_prev,
                       const Eigen::Matrix<double, 6, 6>& covariance);
  // Whether the propagated state is still worth a pose (the lost rule above).
  bool Trustworthy() const;
  // Whether the state's speed is at most twice the body's at the last visual fix (or 1 m/s): a
  // carried state faster than that has diverged (a gyroscope bias the weak frames before the
  // stretch pulled off tilts it, and the velocity runs away), so no map resumes from it.
  bool SpeedPlausible() const;

  // Local BA estimated the state of a keyframe at camera time t_ns (its pose, the body's velocity
  // and the biases, with gravity in the world): the state is that one propagated to the state's
  // time by the IMU (the covariance is kept). False (state unchanged) when not initialised, t_ns
  // is after the state's time or the samples do not cover the interval.
  bool Rebase(int64_t t_ns, const Rigid3d& cam_from_world, const Eigen::Vector3d& v_world_body,
              const ImuBias& bias, const Eigen::Vector3d& g_world);
  // The world moved (loop correction, merge): the state follows, new_from_old mapping old world
  // coordinates to new ones.
  void ChangeWorld(const Rigid3d& new_from_old);
  // Forgets the state and the initialisation window (lost; another map's world). The biases are
  // kept as the next initialisation's start.
  void Reset();

  bool initialised() const { return initialised_; }
  const InertialState& state() const { return state_; }
  int64_t state_t_ns() const { return state_t_ns_; }
  Rigid3d cam_from_world() const { return CamFromWorld(state_.nav, options_.body_from_cam); }
  const Eigen::Vector3d& g_world() const { return state_.g_world; }
  double seconds_without_vision() const { return SecondsBetween(last_visual_t_ns_, state_t_ns_); }

  // For the run's report (metrics.json).
  struct Report {
    std::optional<int64_t> first_init_t_ns;  ///< camera time of the first initialisation [ns]
    std::optional<int64_t> first_pose_t_ns;  ///< camera time of the first pose it was given [ns]
    int initialisations = 0;  ///< successful (after a reset too), refinements not counted
    int refinements = 0;
    /// Refinements not taken: no better fit than the initialisation's, or too far from it
    int rejected_refinements = 0;
    std::string last_failure;  ///< the last initialisation attempt's reason, if it failed
    /// Frames without vision whose velocity the non-holonomic constraint held
    int nonholonomic_updates = 0;
    /// Frames without vision conditioned on zero velocity (the IMU at rest)
    int zero_velocity_updates = 0;
    /// Frames without vision conditioned on the velocity the optical flow measured
    int flow_updates = 0;
    /// RMS of the velocity across the axis of travel over speed, tracked driving so far (-1:
    /// not measured yet, less than 2 s of it)
    double travel_side_ratio = -1.0;
  };
  const Report& report() const { return report_; }

 private:
  void TryInitialise(bool refine);
  // A tracked frame's body velocity (the state after its correction) into the axis of travel.
  void LearnTravel(const InertialState& state, int64_t t_ns);
  // The directions across the axis of travel and the constraint's sigma, when the rig moves as
  // a ground vehicle (nonholonomic_max_side_ratio); false otherwise.
  bool Nonholonomic(Eigen::Matrix<double, 2, 3>* across_body, double* sigma_mps) const;
  bool PropagateState(int64_t t_ns, InertialState* out) const;

  InertialOptions options_;
  ImuNoiseOptions noise_;
  ImuBuffer imu_;
  struct TimedPose {
    int64_t t_ns;
    Rigid3d world_from_body;
  };
  std::deque<TimedPose> window_;  ///< tracked poses, the last window_s of them
  bool initialised_ = false;
  int64_t init_t_ns_ = 0;  ///< when the state was last initialised
  bool refined_ = false;
  std::optional<int64_t>
      last_attempt_t_ns_;  ///< the last initialisation attempt (none: since reset)
  InertialState state_;
  int64_t state_t_ns_ = 0;
  ImuBias bias_start_;                  ///< the next initialisation's linearisation point
  bool bias_known_ = false;             ///< an initialisation succeeded before (bias_start_ is its)
  double last_visual_speed_mps_ = 0.0;  ///< the body's speed at the last visual fix [m/s]
  double init_fit_sigma_radps_ = 0.0;   ///< the initialisation's gyroscope-bias uncertainty
  int64_t last_visual_t_ns_ = 0;        ///< camera time of the last visual correction
  Eigen::Vector3d last_visual_p_ = Eigen::Vector3d::Zero();  ///< body position then [m]
  double driven_m_ = 0.0;  ///< path of the propagated state since then [m]
  // The axis of travel in the body frame, from tracked frames faster than kTravelMinSpeedMps
  // (kept across resets: the rig's kinematics, not a map's): sums of the unit body velocity's
  // and the body velocity's outer products, and the tracked time they span.
  Eigen::Matrix3d travel_direction_scatter_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d travel_velocity_scatter_ = Eigen::Matrix3d::Zero();
  int travel_samples_ = 0;
  double travel_s_ = 0.0;
  std::optional<int64_t> travel_last_t_ns_;
  // What they give once measured (report_.travel_side_ratio >= 0): the two body directions
  // across the axis, and the RMS speed along them [m/s].
  Eigen::Matrix<double, 2, 3> travel_across_body_ = Eigen::Matrix<double, 2, 3>::Zero();
  double travel_side_speed_mps_ = 0.0;
  Report report_;
};

}  // namespace slslam
