#include "slslam/tracking/inertial_estimator.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"

namespace slslam {

namespace {

// Initial standard deviations of the state's error after an initialisation: the pose is the
// camera's (about a centimetre and half a degree after a few frames of stereo), velocity and
// biases what the initialisation's fit leaves of a few seconds of motion.
constexpr double kInitRotationSigmaRad = 0.01;
constexpr double kInitPositionSigmaM = 0.01;
constexpr double kInitVelocitySigmaMps = 0.05;
constexpr double kInitAccBiasSigmaMps2 = 0.1;
// ... and of gravity's direction: about half a degree (the accelerometer bias's share at rest).
constexpr double kInitGravitySigmaMps2 = 0.1;
// Poses the initialisation uses are at least this far apart [s] (20 Hz at most).
constexpr double kInitPoseSpacingS = 0.05;
// The lost rule's distance driven without vision is at most what this many times the speed at
// the last visual fix covers.
constexpr double kMaxSpeedRatio = 2.0;
// A state slower than this is plausible whatever the speed at the last visual fix (a start from
// rest in the dark) [m/s].
constexpr double kPlausibleSpeedFloorMps = 1.0;
// An initialisation that failed is tried again after this much more camera time [s].
constexpr double kInitRetryS = 0.25;
// The axis of travel (nonholonomic_max_side_ratio): learned from tracked frames at least this
// fast (slower, the velocity estimate's noise decides the direction) [m/s], over at least this
// much tracked driving [s], a gap between tracked frames counting as this much at most [s].
constexpr double kTravelMinSpeedMps = 0.2;
constexpr double kTravelMinSeconds = 2.0;
constexpr double kTravelMaxFrameIntervalS = 0.2;
// The IMU samples the rest detector looks at (zero_velocity_max_statistic) [s], and the
// chi-square value (3 degrees of freedom, 99.9 %) past which the state's velocity disagrees.
constexpr double kRestWindowS = 0.5;
constexpr double kRestGateChi2 = 16.27;
// The flow's velocity taken unless the state disagrees beyond 99.9 % (as kRestGateChi2; 1 degree
// of freedom for the speed along the axis of travel alone)
constexpr double kFlowGateChi2Along = 10.83;

// An update corrected gravity in the world: its magnitude is known, only the direction is kept.
void KeepGravityMagnitude(double gravity_mps2, InertialState* state) {
  state->g_world = state->g_world.normalized() * gravity_mps2;
}

// The initial covariance, gravity's uncertainty across its direction only (its magnitude is
// known).
Matrix18d InitialCovariance(const Eigen::Vector3d& g_world, double gyro_bias_sigma_radps,
                            double acc_bias_sigma_mps2) {
  Eigen::Matrix<double, 18, 1> sigma;
  sigma << Eigen::Vector3d::Constant(kInitRotationSigmaRad),
      Eigen::Vector3d::Constant(kInitPositionSigmaM),
      Eigen::Vector3d::Constant(kInitVelocitySigmaMps),
      Eigen::Vector3d::Constant(gyro_bias_sigma_radps),
      Eigen::Vector3d::Constant(std::min(acc_bias_sigma_mps2, kInitAccBiasSigmaMps2)),
      Eigen::Vector3d::Zero();
  Matrix18d P = sigma.cwiseAbs2().asDiagonal();
  const Eigen::Vector3d u = g_world.normalized();
  P.bottomRightCorner<3, 3>() = kInitGravitySigmaMps2 * kInitGravitySigmaMps2 *
                                (Eigen::Matrix3d::Identity() - u * u.transpose());
  return P;
}

}  // namespace

ImuNoiseOptions InertialOptions::Noise() const {
  ImuNoiseOptions noise;
  noise.gyro_noise_density = gyro_noise_density;
  noise.acc_noise_density = acc_noise_density;
  noise.gyro_random_walk = gyro_random_walk;
  noise.acc_random_walk = acc_random_walk;
  noise.gravity_mps2 = gravity_mps2;
  return noise;
}

InertialInitOptions InertialOptions::Init() const {
  InertialInitOptions init;
  init.gravity_mps2 = gravity_mps2;
  init.gravity_tolerance_mps2 = gravity_tolerance_mps2;
  init.acc_bias_prior_mps2 = acc_bias_prior_mps2;
  return init;
}

InertialEstimator::InertialEstimator(const InertialOptions& options)
    : options_(options), noise_(options.Noise()) {
  options_.Check();
}

void InertialEstimator::AddImu(int64_t t_imu_ns, const Eigen::Vector3d& gyro_radps,
                               const Eigen::Vector3d& acc_mps2) {
  imu_.Add(t_imu_ns, gyro_radps, acc_mps2);
}

bool InertialEstimator::PropagateState(int64_t t_ns, InertialState* out) const {
  if (!initialised_) return false;
  if (!(t_ns > state_t_ns_)) {
    *out = state_;
    return t_ns == state_t_ns_;
  }
  ImuPreintegration pre(state_.bias, noise_);
  const int64_t offset_ns = options_.time_offset_ns();
  if (!imu_.Preintegrate(state_t_ns_ - offset_ns, t_ns - offset_ns, options_.max_sample_gap_s,
                         &pre)) {
    return false;
  }
  *out = slslam::Propagate(state_, pre);
  return true;
}

bool InertialEstimator::Predict(int64_t t_ns, InertialState* out) const {
  return PropagateState(t_ns, out);
}

bool InertialEstimator::PosePriorAt(int64_t t_ns, PosePrior* prior) const {
  InertialState predicted;
  if (!PropagateState(t_ns, &predicted)) return false;
  prior->mean = CamFromWorld(predicted.nav, options_.body_from_cam);
  prior->information = CameraPosePriorInformation(predicted, options_.body_from_cam);
  return prior->information.allFinite();
}

void InertialEstimator::AddVisualPose(int64_t t_ns, const Rigid3d& cam_from_world,
                                      const Matrix6d& information, bool with_prior,
                                      const Eigen::Vector3d& unobserved_world) {
  // A pose that leaves a direction unobserved (parallel lines alone) is no pose for the
  // initialisation's window, and no visual fix for the lost rule: the distance driven goes on.
  const bool full = unobserved_world.isZero(0.0);
  if (!full && (!initialised_ || !(t_ns > state_t_ns_))) return;
  if (!report_.first_pose_t_ns) report_.first_pose_t_ns = t_ns;
  const Rigid3d world_from_body = cam_from_world.Inverse() * options_.body_from_cam.Inverse();
  if (full) {
    if (!window_.empty() && !(t_ns > window_.back().t_ns)) return;  // (a frame given twice)
    window_.push_back({t_ns, world_from_body});
    while (window_.size() > 2 && SecondsBetween(window_[1].t_ns, t_ns) >= options_.window_s) {
      window_.pop_front();
    }
    imu_.DropBefore(window_.front().t_ns - options_.time_offset_ns());
  }
  if (!initialised_) {
    TryInitialise(/*refine=*/false);
    return;
  }
  InertialState predicted;
  if (!PropagateState(t_ns, &predicted)) {  // samples missing: start again from this pose
    Reset();
    window_.push_back({t_ns, world_from_body});
    return;
  }
  const Rigid3d predicted_cam = CamFromWorld(predicted.nav, options_.body_from_cam);
  bool conditioned = false;
  if (!information.isZero(0.0)) {
    // The posterior of the pose given the prediction and the images, with the images'
    // information scaled (visual_information_scale).
    const Matrix6d prior = CameraPosePriorInformation(predicted, options_.body_from_cam);
    const double s = options_.visual_information_scale;
    const Vector6d d = LeftTangent(cam_from_world, predicted_cam);
    // Information of the images alone, and the images' estimate times it (in the tangent at the
    // prediction): from the optimiser's posterior (prior + images) when it had the prior.
    Matrix6d visual = with_prior ? Matrix6d(information - prior) : information;
    Vector6d visual_times_d = with_prior ? Vector6d(information * d) : Vector6d(visual * d);
    if (!full) {
      // The images' Gaussian marginalised over the direction (a camera moved by x along it has
      // the left tangent (-R_cw x, 0)): the Schur complement of its information along u, not the
      // projection, which would read the images as measuring zero motion along it.
      Vector6d u = Vector6d::Zero();
      u.head<3>() = (predicted_cam.rotation * unobserved_world).normalized();
      const Vector6d Vu = visual * u;
      const double uVu = u.dot(Vu);
      if (uVu > 1e-12 * std::max(1.0, visual.trace())) {
        visual_times_d -= Vu * (u.dot(visual_times_d) / uVu);
        visual -= Vu * Vu.transpose() / uVu;
      }
    }
    const Matrix6d posterior = prior + s * visual;
    const Eigen::LDLT<Matrix6d> ldlt(posterior);
    if (ldlt.info() == Eigen::Success && ldlt.isPositive() && posterior.allFinite()) {
      const Vector6d d_post = ldlt.solve(s * visual_times_d);
      conditioned = ConditionOnCameraPose(LeftPlus(d_post, predicted_cam), posterior,
                                          options_.body_from_cam, &predicted);
      if (conditioned) KeepGravityMagnitude(options_.gravity_mps2, &predicted);
    }
  }
  if (!conditioned) {
    // A pose without an uncertainty (relocalised): taken as it is, velocity and biases kept.
    predicted.nav.R_world_body = Eigen::Quaterniond(world_from_body.rotation).normalized();
    predicted.nav.p_world_body = world_from_body.translation;
    const Matrix18d kept = predicted.covariance;
    predicted.covariance = InitialCovariance(predicted.g_world, options_.gyro_bias_sigma_radps,
                                             options_.acc_bias_prior_mps2);
    predicted.covariance.bottomRightCorner<12, 12>() = kept.bottomRightCorner<12, 12>();
  }
  if (full && conditioned) LearnTravel(predicted, t_ns);
  if (full) {
    last_visual_t_ns_ = t_ns;
    last_visual_p_ = predicted.nav.p_world_body;
    last_visual_speed_mps_ = predicted.nav.v_world_body.norm();
    driven_m_ = 0.0;
  } else {
    driven_m_ += (predicted.nav.p_world_body - state_.nav.p_world_body).norm();
  }
  state_ = predicted;
  state_t_ns_ = t_ns;
  if (!refined_ && SecondsBetween(init_t_ns_, t_ns) >= options_.refine_after_s) {
    TryInitialise(/*refine=*/true);
  }
}

void InertialEstimator::LearnTravel(const InertialState& state, int64_t t_ns) {
  const std::optional<int64_t> last = travel_last_t_ns_;
  travel_last_t_ns_ = t_ns;
  const Eigen::Vector3d v_body =
      state.nav.R_world_body.toRotationMatrix().transpose() * state.nav.v_world_body;
  const double speed = v_body.norm();
  if (!last || !(speed >= kTravelMinSpeedMps) || !v_body.allFinite()) return;
  const Eigen::Vector3d u = v_body / speed;
  travel_direction_scatter_ += u * u.transpose();
  travel_velocity_scatter_ += v_body * v_body.transpose();
  ++travel_samples_;
  // (a gap between tracked frames counts as one frame interval at most)
  travel_s_ += std::min(SecondsBetween(*last, t_ns), kTravelMaxFrameIntervalS);
  if (travel_s_ < kTravelMinSeconds) return;
  // The axis is the direction scatter's principal eigenvector (driving backwards keeps it); the
  // two others span the directions across it (eigenvalues in increasing order).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(travel_direction_scatter_);
  const Eigen::Matrix3d& V = eig.eigenvectors();
  report_.travel_side_ratio =
      std::sqrt(std::max(0.0, 1.0 - eig.eigenvalues()(2) / travel_samples_));
  travel_across_body_.row(0) = V.col(0).transpose();
  travel_across_body_.row(1) = V.col(1).transpose();
  const Eigen::Vector3d f = V.col(2);
  const double side_ms2 =
      (travel_velocity_scatter_.trace() - f.dot(travel_velocity_scatter_ * f)) / travel_samples_;
  travel_side_speed_mps_ = std::sqrt(std::max(0.0, side_ms2));
}

bool InertialEstimator::Nonholonomic(Eigen::Matrix<double, 2, 3>* across_body,
                                     double* sigma_mps) const {
  // (travel_side_ratio is measured once kTravelMinSeconds of driving were tracked)
  if (!(options_.nonholonomic_max_side_ratio > 0.0) || !(report_.travel_side_ratio >= 0.0) ||
      report_.travel_side_ratio > options_.nonholonomic_max_side_ratio) {
    return false;
  }
  *across_body = travel_across_body_;
  *sigma_mps = std::max(options_.nonholonomic_sigma_mps, travel_side_speed_mps_);
  return true;
}

bool InertialEstimator::Propagate(int64_t t_ns) {
  InertialState next;
  if (!PropagateState(t_ns, &next)) return false;
  Eigen::Matrix<double, 2, 3> across;
  double sigma = 0.0;
  if (Nonholonomic(&across, &sigma) && ConditionOnBodyVelocity(across, sigma, &next)) {
    KeepGravityMagnitude(options_.gravity_mps2, &next);
    ++report_.nonholonomic_updates;
  }
  if (options_.zero_velocity_max_statistic > 0.0) {
    const int64_t t_imu_ns = t_ns - options_.time_offset_ns();
    const std::optional<double> rest = imu_.RestStatistic(
        t_imu_ns - NsFromSeconds(kRestWindowS), t_imu_ns, next.bias, options_.gravity_mps2,
        options_.gyro_noise_density, options_.acc_noise_density);
    if (rest && *rest <= options_.zero_velocity_max_statistic &&
        ConditionOnBodyVelocity(Eigen::Matrix3d::Identity(), options_.zero_velocity_sigma_mps,
                                &next, kRestGateChi2)) {
      KeepGravityMagnitude(options_.gravity_mps2, &next);
      ++report_.zero_velocity_updates;
    }
  }
  driven_m_ += (next.nav.p_world_body - state_.nav.p_world_body).norm();
  state_ = next;
  state_t_ns_ = std::max(state_t_ns_, t_ns);
  return true;
}

bool InertialEstimator::AddCameraMotion(int64_t prev_t_ns, int64_t t_ns,
                                        const Rigid3d& cur_from_prev,
                                        const Eigen::Matrix<double, 6, 6>& covariance_6) {
  if (!initialised_ || options_.flow_min_inliers <= 0 || t_ns != state_t_ns_) return false;
  const double dt = SecondsBetween(prev_t_ns, t_ns);
  if (!(dt > 0.0) || dt > kTravelMaxFrameIntervalS) return false;
  // The body's displacement over the interval in its current frame: minus the translation of
  // cur_body_from_prev_body = body_from_cam * cur_from_prev * cam_from_body, the lever arm of
  // the camera turning about the body included. That translation is
  // R_body_cam (R_cur_prev t_cam_body + t_cur_prev) + t_body_cam: its Jacobian is
  // -R_body_cam [R_cur_prev t_cam_body]x in the rotation (Exp(dtheta) R_cur_prev) and
  // R_body_cam in the translation.
  const Rigid3d& body_from_cam = options_.body_from_cam;
  const Rigid3d cam_from_body = body_from_cam.Inverse();
  const Rigid3d cur_body_from_prev_body = body_from_cam * cur_from_prev * cam_from_body;
  const Eigen::Vector3d v_body = -cur_body_from_prev_body.translation / dt;
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>() =
      -body_from_cam.rotation * Skew(cur_from_prev.rotation * cam_from_body.translation);
  J.rightCols<3>() = body_from_cam.rotation;
  Eigen::Matrix3d covariance = J * covariance_6 * J.transpose() / (dt * dt);
  covariance = 0.5 * (covariance + covariance.transpose());
  const double floor_sq = options_.flow_sigma_mps * options_.flow_sigma_mps;
  // each axis at least the floor (the eigenvalues raised to it)
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance);
  if (eig.info() != Eigen::Success) return false;
  covariance = eig.eigenvectors() * eig.eigenvalues().cwiseMax(floor_sq).asDiagonal() *
               eig.eigenvectors().transpose();
  InertialState next = state_;
  // A ground vehicle: the flow's speed along its axis of travel only, the directions across it
  // are the non-holonomic constraint's (the flow's errors across the path correlate with its
  // rotation and with the headlamp's shading moving over the relief).
  Eigen::Matrix<double, 2, 3> across;
  double across_sigma = 0.0;
  bool taken = false;
  if (Nonholonomic(&across, &across_sigma)) {
    const Eigen::Matrix<double, 1, 3> along = across.row(0).cross(across.row(1)).normalized();
    taken = ConditionOnMeasuredBodyVelocity(
        along, Eigen::VectorXd::Constant(1, along.dot(v_body)),
        Eigen::MatrixXd::Constant(1, 1, along.dot(covariance * along.transpose())), &next,
        kFlowGateChi2Along);
  } else {
    taken = ConditionOnMeasuredBodyVelocity(Eigen::Matrix3d::Identity(), v_body, covariance, &next,
                                            kRestGateChi2);
  }
  if (!taken) return false;
  KeepGravityMagnitude(options_.gravity_mps2, &next);
  state_ = next;
  ++report_.flow_updates;
  return true;
}

bool InertialEstimator::Trustworthy() const {
  if (!initialised_) return false;
  // The distance driven is the propagated state's, which a drifting estimate inflates itself
  // (issue 62's dark relief lining: 5.5 times the true path, and the bound with it): at most
  // what twice the speed at the last visual fix covers.
  const double driven =
      std::min(driven_m_, kMaxSpeedRatio * last_visual_speed_mps_ * seconds_without_vision());
  const double bound = std::max(options_.lost_sigma_min_m, options_.lost_sigma_fraction * driven);
  return state_.PositionSigma() <= bound && seconds_without_vision() <= options_.max_gap_s;
}

bool InertialEstimator::SpeedPlausible() const {
  return initialised_ &&
         state_.nav.v_world_body.norm() <=
             std::max(kMaxSpeedRatio * last_visual_speed_mps_, kPlausibleSpeedFloorMps);
}

bool InertialEstimator::Rebase(int64_t t_ns, const Rigid3d& cam_from_world,
                               const Eigen::Vector3d& v_world_body, const ImuBias& bias,
                               const Eigen::Vector3d& g_world) {
  if (!initialised_ || !(t_ns <= state_t_ns_) || !g_world.allFinite()) return false;
  const Rigid3d world_from_body = cam_from_world.Inverse() * options_.body_from_cam.Inverse();
  NavState at_keyframe;
  at_keyframe.R_world_body = Eigen::Quaterniond(world_from_body.rotation).normalized();
  at_keyframe.p_world_body = world_from_body.translation;
  at_keyframe.v_world_body = v_world_body;
  NavState now = at_keyframe;
  if (t_ns < state_t_ns_) {
    ImuPreintegration pre(bias, noise_);
    const int64_t offset_ns = options_.time_offset_ns();
    if (!imu_.Preintegrate(t_ns - offset_ns, state_t_ns_ - offset_ns, options_.max_sample_gap_s,
                           &pre)) {
      return false;
    }
    now = pre.Predict(at_keyframe, bias, g_world);
  }
  state_.nav = now;
  state_.bias = bias;
  state_.g_world = g_world;
  return true;
}

void InertialEstimator::ChangeWorld(const Rigid3d& new_from_old) {
  const Eigen::Matrix3d& R = new_from_old.rotation;
  for (TimedPose& pose : window_) pose.world_from_body = new_from_old * pose.world_from_body;
  last_visual_p_ = new_from_old * last_visual_p_;
  if (!initialised_) return;
  state_.nav.R_world_body = Eigen::Quaterniond(R * state_.nav.R_world_body.toRotationMatrix());
  state_.nav.p_world_body = new_from_old * state_.nav.p_world_body;
  state_.nav.v_world_body = R * state_.nav.v_world_body;
  state_.g_world = R * state_.g_world;
  // dtheta is in the body frame and the biases in the IMU's: dp, dv and dg rotate.
  Matrix18d C = Matrix18d::Identity();
  C.block<3, 3>(3, 3) = R;
  C.block<3, 3>(6, 6) = R;
  C.block<3, 3>(15, 15) = R;
  state_.covariance = C * state_.covariance * C.transpose();
}

void InertialEstimator::Reset() {
  if (initialised_) {
    bias_start_ = state_.bias;
    bias_known_ = true;
  }
  initialised_ = false;
  refined_ = false;
  window_.clear();
  last_attempt_t_ns_.reset();
  travel_last_t_ns_.reset();  // (the axis learned so far is kept)
}

void InertialEstimator::TryInitialise(bool refine) {
  if (window_.size() < 3) return;
  const int64_t t_last = window_.back().t_ns;
  if (SecondsBetween(window_.front().t_ns, t_last) < options_.min_window_s) return;
  if (!refine && last_attempt_t_ns_ && SecondsBetween(*last_attempt_t_ns_, t_last) < kInitRetryS) {
    return;
  }
  last_attempt_t_ns_ = t_last;
  std::vector<Rigid3d> poses;
  std::vector<int64_t> times;
  for (const TimedPose& pose : window_) {
    if (times.empty() || SecondsBetween(times.back(), pose.t_ns) >= kInitPoseSpacingS) {
      poses.push_back(pose.world_from_body);
      times.push_back(pose.t_ns);
    }
  }
  if (times.back() != t_last) {  // the newest pose replaces the last one kept (closer than that)
    poses.back() = window_.back().world_from_body;
    times.back() = t_last;
  }
  if (poses.size() < 3) return;
  double path_m = 0.0;
  for (size_t k = 1; k < poses.size(); ++k) {
    path_m += (poses[k].translation - poses[k - 1].translation).norm();
  }
  if (refine && path_m < options_.refine_min_path_m) return;
  const ImuBias start = refine ? state_.bias : bias_start_;
  std::vector<ImuPreintegration> pre;
  pre.reserve(poses.size() - 1);
  for (size_t k = 0; k + 1 < poses.size(); ++k) {
    pre.emplace_back(start, noise_);
    if (!imu_.Preintegrate(times[k] - options_.time_offset_ns(),
                           times[k + 1] - options_.time_offset_ns(), options_.max_sample_gap_s,
                           &pre.back())) {
      report_.last_failure = "IMU samples missing between tracked frames";
      return;
    }
  }
  InertialInitOptions init = options_.Init();
  // Once a fit has given the gyroscope bias, a new map's initialisation (after a loss: the
  // weakest stretch of tracking) starts from it, held as the state held it (a fit on the lost
  // stretch of issue 62's flat lining put it 2.4e-2 rad/s off).
  if (!refine && bias_known_) init.gyro_bias_prior_radps = options_.gyro_bias_sigma_radps;
  const InertialInitResult r = InitialiseInertial(poses, pre, init);
  if (!r.success) {
    report_.last_failure = r.reason;
    return;
  }
  report_.last_failure.clear();
  // The fit's gyroscope-bias uncertainty: the rotation misfit of consecutive poses over the
  // window's span (the increments' sum telescopes to the first and last poses' errors).
  const double span_s = std::max(SecondsBetween(times.front(), times.back()), 1e-3);
  const double fit_sigma = r.rotation_rms_rad / span_s;
  if (refine) {
    refined_ = true;  // (one refinement per initialisation, taken or not)
    // Taken when it is the better fit of the two and agrees with the first within 3 of their
    // sigmas: a fit on a window tracked through weak texture can be far off (issue 62's dark
    // relief lining: its 1 s initialisation 2.8e-3 rad/s), and the state holds its bias tight.
    const double bound = 3.0 * std::hypot(init_fit_sigma_radps_, fit_sigma);
    if (!(fit_sigma < init_fit_sigma_radps_) ||
        (r.bias.gyro - state_.bias.gyro).cwiseAbs().maxCoeff() > bound) {
      ++report_.rejected_refinements;
      return;
    }
    state_.g_world = r.g_world;
    ++report_.refinements;
    state_.bias = r.bias;
    state_.nav.v_world_body = r.v_world.back();
    return;
  }
  state_.nav.R_world_body = Eigen::Quaterniond(poses.back().rotation).normalized();
  state_.nav.p_world_body = poses.back().translation;
  state_.nav.v_world_body = r.v_world.back();
  state_.bias = r.bias;
  state_.g_world = r.g_world;
  state_.covariance = InitialCovariance(
      r.g_world, std::max(options_.gyro_bias_sigma_radps, fit_sigma), options_.acc_bias_prior_mps2);
  state_t_ns_ = times.back();
  last_visual_t_ns_ = state_t_ns_;
  last_visual_p_ = state_.nav.p_world_body;
  last_visual_speed_mps_ = state_.nav.v_world_body.norm();
  driven_m_ = 0.0;
  initialised_ = true;
  init_t_ns_ = state_t_ns_;
  init_fit_sigma_radps_ = fit_sigma;
  ++report_.initialisations;
  if (!report_.first_init_t_ns) report_.first_init_t_ns = state_t_ns_;
}

void InertialOptions::Check() const {
  Require(body_from_cam.rotation.allFinite() && body_from_cam.translation.allFinite(),
          "tracking.imu.body_from_cam is not finite");
  const double det = body_from_cam.rotation.determinant();
  SLSLAM_CHECK(
      std::abs(det - 1.0) < 1e-6 && (body_from_cam.rotation * body_from_cam.rotation.transpose() -
                                     Eigen::Matrix3d::Identity())
                                            .norm() < 1e-6,
      "tracking.imu.body_from_cam: the rotation is not orthonormal (det ", det, ")");
  CheckInRange("tracking.imu.time_offset_s", time_offset_s, -10.0, 10.0);
  CheckInRange("tracking.imu.gyro_noise_density", gyro_noise_density, 0.0, 1.0);
  CheckInRange("tracking.imu.acc_noise_density", acc_noise_density, 0.0, 1.0);
  CheckInRange("tracking.imu.gyro_random_walk", gyro_random_walk, 0.0, 1.0);
  CheckInRange("tracking.imu.acc_random_walk", acc_random_walk, 0.0, 1.0);
  SLSLAM_CHECK(gravity_mps2 > 0.0 && gravity_mps2 < 20.0,
               "tracking.imu.gravity_mps2 must be in (0, 20), got ", gravity_mps2);
  CheckAboveInRange("tracking.imu.gravity_tolerance_mps2", gravity_tolerance_mps2, 0.0, 100.0);
  CheckAboveInRange("tracking.imu.acc_bias_prior_mps2", acc_bias_prior_mps2, 0.0, 100.0);
  CheckAboveInRange("tracking.imu.gyro_bias_sigma_radps", gyro_bias_sigma_radps, 0.0, 1.0);
  CheckInRange("tracking.imu.window_s", window_s, 0.1, 1000.0);
  CheckInRange("tracking.imu.min_window_s", min_window_s, 0.05, 1000.0);
  SLSLAM_CHECK(min_window_s <= window_s, "tracking.imu.window_s (", window_s,
               ") must not be below tracking.imu.min_window_s (", min_window_s, ")");
  CheckInRange("tracking.imu.refine_after_s", refine_after_s, 0.0, 1e6);
  CheckInRange("tracking.imu.refine_min_path_m", refine_min_path_m, 0.0, 1e6);
  CheckAboveInRange("tracking.imu.max_sample_gap_s", max_sample_gap_s, 0.0, 10.0);
  CheckInRange("tracking.imu.lost_sigma_fraction", lost_sigma_fraction, 0.0, 10.0);
  CheckInRange("tracking.imu.nonholonomic_max_side_ratio", nonholonomic_max_side_ratio, 0.0, 1.0);
  CheckAboveInRange("tracking.imu.nonholonomic_sigma_mps", nonholonomic_sigma_mps, 0.0, 100.0);
  CheckInRange("tracking.imu.zero_velocity_max_statistic", zero_velocity_max_statistic, 0.0, 1e6);
  CheckAboveInRange("tracking.imu.zero_velocity_sigma_mps", zero_velocity_sigma_mps, 0.0, 100.0);
  CheckInRange("tracking.imu.flow_min_inliers", flow_min_inliers, 0, 100000);
  CheckAboveInRange("tracking.imu.flow_sigma_mps", flow_sigma_mps, 0.0, 100.0);
  CheckInRange("tracking.imu.lost_sigma_min_m", lost_sigma_min_m, 0.0, 1e6);
  CheckInRange("tracking.imu.max_gap_s", max_gap_s, 0.0, 1e6);
  CheckInRange("tracking.imu.weak_update_min_inliers", weak_update_min_inliers, 0, 100000);
  CheckInRange("tracking.imu.weak_update_min_lines", weak_update_min_lines, 0, 100000);
  CheckInRange("tracking.imu.keyframe_min_stereo_lines", keyframe_min_stereo_lines, 0, 100000);
  CheckInRange("tracking.imu.local_ba_keyframes", local_ba_keyframes, 0, 1000);
  CheckInRange("tracking.imu.keyframe_interval_s", keyframe_interval_s, 0.0, 1e6);
  CheckInRange("tracking.imu.visual_information_scale", visual_information_scale, 1e-6, 1e6);
}

}  // namespace slslam
