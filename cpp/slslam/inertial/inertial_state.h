// The inertial state of a camera-IMU rig between frames: the body's navigation state, the IMU
// biases and their joint covariance, carried from one frame to the next by a preintegrated IMU
// interval (imu_preintegration.h) and corrected by a camera pose (the visual-inertial tracker's
// per-frame estimate, tracking/inertial_estimator.h).
//
// Frames: world = the frame the state is expressed in (a visual map's world: gravity is the
// vector g_world in it, not necessarily along -z); body = the IMU frame; cam = the rectified left
// camera, with body_from_cam the camera-IMU extrinsics (Kalibr's T_cam_imu inverted).
//
// Error state (18): dtheta (rotation, right-perturbed in the body frame:
// R_world_body = R_hat Exp(dtheta)), dp and dv (world frame, additive), dbg and dba (additive),
// dg (gravity in the world, additive), in this order. Gravity is part of the state because the
// worlds it is used in are not gravity-aligned: the initialisation's estimate of its direction
// is corrected as the camera goes on (a constant accelerometer bias cannot absorb a tilt of
// gravity once the body turns). A camera pose's error is the pose manifold's left tangent
// (optimization/manifolds.h: cam_from_world = Exp(rho, omega) * cam_from_world_hat).
#pragma once

#include <cstdint>
#include <deque>
#include <limits>
#include <optional>

#include <Eigen/Core>

#include "slslam/core/rigid3.h"
#include "slslam/inertial/imu_preintegration.h"

namespace slslam {

using Matrix18d = Eigen::Matrix<double, 18, 18>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

struct InertialState {
  NavState nav;                                       ///< body in the world
  ImuBias bias;                                       ///< [rad/s], [m/s^2]
  Eigen::Vector3d g_world = Eigen::Vector3d::Zero();  ///< gravity in the world [m/s^2]
  Matrix18d covariance = Matrix18d::Zero();           ///< of the error state above

  /// Position standard deviation: sqrt of the trace of the dp block [m].
  double PositionSigma() const;
};

// The state after the interval `pre` (integrated from the sample times of the start state, with
// any linearisation bias: the increments are corrected to `start.bias`), under the state's
// gravity.
// The covariance is propagated through the first-order error dynamics of the increments
// (Forster et al. 2017) plus the bias random walk of `pre.noise()` over the interval.
InertialState Propagate(const InertialState& start, const ImuPreintegration& pre);

// The 18 x 18 Jacobian of Propagate's error state at the end w.r.t. the one at the start (what
// the covariance is propagated with; a gtest compares it to finite differences).
Matrix18d PropagationJacobian(const InertialState& start, const ImuPreintegration& pre);

// The left tangent d = (rho, omega) with a = Exp(d) * b (the pose manifold's Minus), and its
// inverse.
Vector6d LeftTangent(const Rigid3d& a, const Rigid3d& b);
Rigid3d LeftPlus(const Vector6d& d, const Rigid3d& b);

// cam_from_world of the camera on a body at `nav`.
Rigid3d CamFromWorld(const NavState& nav, const Rigid3d& body_from_cam);

// The 6 x 6 Jacobian of the camera pose's left tangent (rho, omega) w.r.t. the body error
// (dtheta, dp) at `nav` (invertible: the two are the same 6 degrees of freedom).
Matrix6d CamTangentFromBodyError(const NavState& nav, const Rigid3d& body_from_cam);

// Conditions the state on a camera pose estimate: `cam_from_world` with the information
// `information` (6 x 6, of the pose's left tangent, as the pose optimiser reports it) is the
// posterior of the state's rotation and position given the images and the state's own marginal
// prior on them (the tracker's visual-inertial pose optimisation), so the rotation and position
// are replaced by it and the velocity and biases move through their cross-covariance with them.
// False (state unchanged) when the information is not positive definite.
bool ConditionOnCameraPose(const Rigid3d& cam_from_world, const Matrix6d& information,
                           const Rigid3d& body_from_cam, InertialState* state);

// Conditions the state on the body's velocity having no component along the rows of
// `directions_body` (unit vectors in the body frame, at most 3): rows * R_world_body^T * v = 0
// within sigma_mps each, an extended Kalman update of the whole error state (a ground vehicle's
// non-holonomic constraint: no velocity across or normal to its direction of travel; all three
// axes: at rest). False (state unchanged) when sigma_mps is not positive, the update is not
// well conditioned, or the innovation's squared Mahalanobis distance passes max_mahalanobis_sq
// (the state disagrees with the constraint: a detection of rest while the state moves).
bool ConditionOnBodyVelocity(const Eigen::Matrix<double, Eigen::Dynamic, 3>& directions_body,
                             double sigma_mps, InertialState* state,
                             double max_mahalanobis_sq = std::numeric_limits<double>::infinity());
// Conditions the state on measured components of the body's velocity: rows * R_world_body^T * v
// = measured within `covariance` [m^2/s^2] (m x m, m at most 3; an odometry of the body's
// motion, the camera's optical flow), the same update and gate as ConditionOnBodyVelocity.
bool ConditionOnMeasuredBodyVelocity(
    const Eigen::Matrix<double, Eigen::Dynamic, 3>& rows, const Eigen::VectorXd& measured,
    const Eigen::MatrixXd& covariance, InertialState* state,
    double max_mahalanobis_sq = std::numeric_limits<double>::infinity());

// The marginal of the state's rotation and position as a prior on the camera pose: its
// information in the left tangent (for the pose optimiser).
Matrix6d CameraPosePriorInformation(const InertialState& state, const Rigid3d& body_from_cam);

// IMU samples in time order, each held until the next one's time. Times are int64 ns on the
// IMU's clock (core/time.h).
class ImuBuffer {
 public:
  // Throws std::invalid_argument on a time not after the last one or a non-finite value.
  void Add(int64_t t_ns, const Eigen::Vector3d& gyro_radps, const Eigen::Vector3d& acc_mps2);
  // Integrates the samples over [t0_ns, t1_ns] (the first sample at or before t0_ns; partial
  // intervals at both ends) into `out`, whose bias_hat and noise are kept. False when the
  // samples do not cover the interval or two are further apart than max_sample_gap_s.
  bool Preintegrate(int64_t t0_ns, int64_t t1_ns, double max_sample_gap_s,
                    ImuPreintegration* out) const;
  // Forgets samples no longer needed for intervals starting at or after t_ns.
  void DropBefore(int64_t t_ns);
  // The samples Preintegrate needs for [t0_ns, t1_ns]: from the last one at or before t0_ns to
  // the last one before t1_ns.
  ImuBuffer Slice(int64_t t0_ns, int64_t t1_ns) const;
  // Whether the body was at rest over [t0_ns, t1_ns] as its samples show it (the SHOE detector
  // of Skog et al. 2010): the mean over the samples of |gyro - bias|^2 / sigma_g^2 +
  // |acc - bias - g u|^2 / sigma_a^2 (u: the mean specific force's direction, g its expected
  // magnitude), sigma the white noise of one sample (density / sqrt(sample interval)), divided
  // by its 6 degrees of freedom: about 1 at rest, far larger in motion (vibration, a turn).
  // Nullopt with fewer than 10 samples in the interval.
  std::optional<double> RestStatistic(int64_t t0_ns, int64_t t1_ns, const ImuBias& bias,
                                      double gravity_mps2, double gyro_noise_density,
                                      double acc_noise_density) const;
  // Appends the samples of `later` after this buffer's last one (those not after it are skipped).
  void Append(const ImuBuffer& later);
  bool empty() const { return samples_.empty(); }
  size_t size() const { return samples_.size(); }

 private:
  struct Sample {
    int64_t t_ns;
    Eigen::Vector3d gyro, acc;
  };
  std::deque<Sample> samples_;
};

}  // namespace slslam
