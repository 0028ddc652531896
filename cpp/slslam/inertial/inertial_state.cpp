#include "slslam/inertial/inertial_state.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "slslam/core/check.h"
#include "slslam/core/time.h"
#include "slslam/geometry/rotation.h"

namespace slslam {

double InertialState::PositionSigma() const {
  return std::sqrt(std::max(0.0, covariance.block<3, 3>(3, 3).trace()));
}

Matrix18d PropagationJacobian(const InertialState& start, const ImuPreintegration& pre) {
  const Eigen::Matrix3d R_i = start.nav.R_world_body.toRotationMatrix();
  const Eigen::Matrix3d dR = pre.CorrectedDeltaR(start.bias);
  const Eigen::Vector3d dv = pre.CorrectedDeltaV(start.bias);
  const Eigen::Vector3d dp = pre.CorrectedDeltaP(start.bias);
  const double dt = pre.dt_s();
  // R_j = R_i Exp(dtheta_i) dR Exp(J_Rg dbg)      -> dtheta_j = dR^T dtheta_i + J_Rg dbg
  // v_j = v_i + g dt + R_i Exp(dtheta_i) dv(b)   -> dv_j = dv_i - R_i [dv]x dtheta_i + R_i J_v db
  // p_j = p_i + v_i dt + g dt^2/2 + R_i Exp(dtheta_i) dp(b)
  // and dg enters the velocity by dt and the position by dt^2 / 2.
  Matrix18d A = Matrix18d::Identity();
  A.block<3, 3>(0, 0) = dR.transpose();
  A.block<3, 3>(0, 9) = pre.dR_dbg();
  A.block<3, 3>(3, 0) = -R_i * Skew(dp);
  A.block<3, 3>(3, 6) = Eigen::Matrix3d::Identity() * dt;
  A.block<3, 3>(3, 9) = R_i * pre.dp_dbg();
  A.block<3, 3>(3, 12) = R_i * pre.dp_dba();
  A.block<3, 3>(6, 0) = -R_i * Skew(dv);
  A.block<3, 3>(6, 9) = R_i * pre.dv_dbg();
  A.block<3, 3>(6, 12) = R_i * pre.dv_dba();
  A.block<3, 3>(3, 15) = 0.5 * dt * dt * Eigen::Matrix3d::Identity();
  A.block<3, 3>(6, 15) = dt * Eigen::Matrix3d::Identity();
  return A;
}

InertialState Propagate(const InertialState& start, const ImuPreintegration& pre) {
  InertialState end;
  end.nav = pre.Predict(start.nav, start.bias, start.g_world);
  end.bias = start.bias;
  end.g_world = start.g_world;
  const Matrix18d A = PropagationJacobian(start, pre);
  // The increments' own noise, (dtheta, dv, dp) in B_i, into (dtheta_j, dp, dv) of the state:
  // dtheta_j is right-perturbed at the end, the increments' at their own end (the same frame).
  const Eigen::Matrix3d R_i = start.nav.R_world_body.toRotationMatrix();
  Eigen::Matrix<double, 18, 9> B = Eigen::Matrix<double, 18, 9>::Zero();
  B.block<3, 3>(0, 0) = Eigen::Matrix3d::Identity();
  B.block<3, 3>(6, 3) = R_i;
  B.block<3, 3>(3, 6) = R_i;
  end.covariance = A * start.covariance * A.transpose() + B * pre.covariance() * B.transpose();
  const ImuNoiseOptions& noise = pre.noise();
  end.covariance.block<3, 3>(9, 9).diagonal().array() +=
      noise.gyro_random_walk * noise.gyro_random_walk * pre.dt_s();
  end.covariance.block<3, 3>(12, 12).diagonal().array() +=
      noise.acc_random_walk * noise.acc_random_walk * pre.dt_s();
  end.covariance = 0.5 * (end.covariance + end.covariance.transpose()).eval();
  return end;
}

Vector6d LeftTangent(const Rigid3d& a, const Rigid3d& b) {
  const Eigen::Matrix3d dR = a.rotation * b.rotation.transpose();
  Vector6d d;
  d.tail<3>() = LogSO3(Eigen::Quaterniond(dR));
  d.head<3>() = a.translation - dR * b.translation;
  return d;
}

Rigid3d LeftPlus(const Vector6d& d, const Rigid3d& b) {
  const Eigen::Matrix3d dR = ExpSO3(d.tail<3>());
  return Rigid3d(dR * b.rotation, dR * b.translation + d.head<3>());
}

Rigid3d CamFromWorld(const NavState& nav, const Rigid3d& body_from_cam) {
  const Rigid3d world_from_body(nav.R_world_body.toRotationMatrix(), nav.p_world_body);
  return (world_from_body * body_from_cam).Inverse();
}

Matrix6d CamTangentFromBodyError(const NavState& nav, const Rigid3d& body_from_cam) {
  // cam_from_world = cam_from_body * body_from_world. With R_wb -> R_wb Exp(dtheta) and
  // p_wb -> p_wb + dp: R_cw -> Exp(-R_cb dtheta) R_cw, and t_cw moves by
  // rho = R_cb [t_bc]x dtheta - R_cw dp beyond the rotation's own Exp(omega) t_cw.
  const Eigen::Matrix3d R_cb = body_from_cam.rotation.transpose();
  const Eigen::Matrix3d R_cw = R_cb * nav.R_world_body.toRotationMatrix().transpose();
  Matrix6d G = Matrix6d::Zero();
  G.block<3, 3>(0, 0) = R_cb * Skew(body_from_cam.translation);
  G.block<3, 3>(0, 3) = -R_cw;
  G.block<3, 3>(3, 0) = -R_cb;
  return G;
}

Matrix6d CameraPosePriorInformation(const InertialState& state, const Rigid3d& body_from_cam) {
  const Matrix6d G = CamTangentFromBodyError(state.nav, body_from_cam);
  const Matrix6d cov = G * state.covariance.topLeftCorner<6, 6>() * G.transpose();
  return cov.ldlt().solve(Matrix6d::Identity());
}

bool ConditionOnCameraPose(const Rigid3d& cam_from_world, const Matrix6d& information,
                           const Rigid3d& body_from_cam, InertialState* state) {
  if (!information.allFinite()) return false;
  const Eigen::LDLT<Matrix6d> info(information);
  if (info.info() != Eigen::Success || !(info.vectorD().minCoeff() > 0.0)) return false;
  const Matrix6d G = CamTangentFromBodyError(state->nav, body_from_cam);
  const Matrix6d G_inv = G.inverse();
  // The estimate's difference from the state's pose, in the body error (dtheta, dp).
  const Vector6d tangent = LeftTangent(cam_from_world, CamFromWorld(state->nav, body_from_cam));
  const Vector6d d_a = G_inv * tangent;
  const Matrix6d cov_post = G_inv * info.solve(Matrix6d::Identity()) * G_inv.transpose();

  constexpr int kRest = 12;  // velocity, biases, gravity
  const Matrix18d& P = state->covariance;
  const Matrix6d P_aa = P.topLeftCorner<6, 6>();
  const Eigen::LDLT<Matrix6d> P_aa_ldlt(P_aa);
  if (P_aa_ldlt.info() != Eigen::Success || !(P_aa_ldlt.vectorD().minCoeff() > 0.0)) return false;
  const Eigen::Matrix<double, kRest, 6> K =
      P_aa_ldlt.solve(P.block<6, kRest>(0, 6)).transpose();  // P_ra P_aa^-1 (P symmetric)
  const Eigen::Matrix<double, kRest, 1> d_r = K * d_a;
  Matrix18d updated;
  updated.topLeftCorner<6, 6>() = cov_post;
  updated.block<kRest, 6>(6, 0) = K * cov_post;
  updated.block<6, kRest>(0, 6) = updated.block<kRest, 6>(6, 0).transpose();
  updated.bottomRightCorner<kRest, kRest>() = P.bottomRightCorner<kRest, kRest>() -
                                              K * P.block<6, kRest>(0, 6) +
                                              K * cov_post * K.transpose();
  state->covariance = 0.5 * (updated + updated.transpose());

  const Rigid3d world_from_body = cam_from_world.Inverse() * body_from_cam.Inverse();
  state->nav.R_world_body = Eigen::Quaterniond(world_from_body.rotation).normalized();
  state->nav.p_world_body = world_from_body.translation;
  state->nav.v_world_body += d_r.head<3>();
  state->bias.gyro += d_r.segment<3>(3);
  state->bias.acc += d_r.segment<3>(6);
  state->g_world += d_r.tail<3>();
  return true;
}

namespace {

// rows * R^T v = measured within noise (m x m): the extended Kalman update of the error state.
bool ConditionOnBodyVelocityRows(const Eigen::Matrix<double, Eigen::Dynamic, 3>& rows,
                                 const Eigen::VectorXd& measured, const Eigen::MatrixXd& noise,
                                 InertialState* state, double max_mahalanobis_sq) {
  const Eigen::Matrix3d R = state->nav.R_world_body.toRotationMatrix();
  const Eigen::Vector3d u = R.transpose() * state->nav.v_world_body;  // the body's velocity
  const Eigen::Index m = rows.rows();
  // With R -> R Exp(dtheta) and v -> v + dv: R^T v -> u + [u]x dtheta + R^T dv.
  Eigen::Matrix<double, Eigen::Dynamic, 18> H =
      Eigen::Matrix<double, Eigen::Dynamic, 18>::Zero(m, 18);
  H.middleCols<3>(0) = rows * Skew(u);
  H.middleCols<3>(6) = rows * R.transpose();
  const Eigen::VectorXd residual = measured - rows * u;
  const Matrix18d& P = state->covariance;
  const Eigen::MatrixXd PHt = P * H.transpose();
  const Eigen::MatrixXd S = H * PHt + noise;
  const Eigen::LDLT<Eigen::MatrixXd> S_ldlt(S);
  if (S_ldlt.info() != Eigen::Success || !(S_ldlt.vectorD().minCoeff() > 0.0)) return false;
  if (!(residual.dot(S_ldlt.solve(residual)) <= max_mahalanobis_sq)) return false;
  const Eigen::Matrix<double, 18, Eigen::Dynamic> K = S_ldlt.solve(PHt.transpose()).transpose();
  const Eigen::Matrix<double, 18, 1> dx = K * residual;
  if (!dx.allFinite()) return false;
  // Joseph form: stays symmetric positive semi-definite with a gain computed in floating point.
  const Matrix18d I_KH = Matrix18d::Identity() - K * H;
  Matrix18d updated = I_KH * P * I_KH.transpose() + K * noise * K.transpose();
  state->covariance = 0.5 * (updated + updated.transpose());
  state->nav.R_world_body =
      (state->nav.R_world_body * Eigen::Quaterniond(ExpSO3(dx.segment<3>(0)))).normalized();
  state->nav.p_world_body += dx.segment<3>(3);
  state->nav.v_world_body += dx.segment<3>(6);
  state->bias.gyro += dx.segment<3>(9);
  state->bias.acc += dx.segment<3>(12);
  state->g_world += dx.segment<3>(15);
  return true;
}

}  // namespace

bool ConditionOnBodyVelocity(const Eigen::Matrix<double, Eigen::Dynamic, 3>& directions_body,
                             double sigma_mps, InertialState* state, double max_mahalanobis_sq) {
  const Eigen::Index m = directions_body.rows();
  if (!(sigma_mps > 0.0) || m == 0 || m > 3 || !directions_body.allFinite()) return false;
  return ConditionOnBodyVelocityRows(directions_body, Eigen::VectorXd::Zero(m),
                                     sigma_mps * sigma_mps * Eigen::MatrixXd::Identity(m, m), state,
                                     max_mahalanobis_sq);
}

bool ConditionOnMeasuredBodyVelocity(const Eigen::Matrix<double, Eigen::Dynamic, 3>& rows,
                                     const Eigen::VectorXd& measured,
                                     const Eigen::MatrixXd& covariance, InertialState* state,
                                     double max_mahalanobis_sq) {
  const Eigen::Index m = rows.rows();
  if (m == 0 || m > 3 || measured.size() != m || covariance.rows() != m || covariance.cols() != m ||
      !rows.allFinite() || !measured.allFinite() || !covariance.allFinite()) {
    return false;
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(covariance);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return false;
  return ConditionOnBodyVelocityRows(rows, measured, covariance, state, max_mahalanobis_sq);
}

void ImuBuffer::Add(int64_t t_ns, const Eigen::Vector3d& gyro_radps,
                    const Eigen::Vector3d& acc_mps2) {
  Require(gyro_radps.allFinite() && acc_mps2.allFinite(), "IMU sample is not finite");
  SLSLAM_CHECK(samples_.empty() || t_ns > samples_.back().t_ns,
               "IMU samples must come in increasing time: ", t_ns, " ns after ",
               samples_.back().t_ns, " ns");
  samples_.push_back({t_ns, gyro_radps, acc_mps2});
}

bool ImuBuffer::Preintegrate(int64_t t0_ns, int64_t t1_ns, double max_sample_gap_s,
                             ImuPreintegration* out) const {
  if (samples_.empty() || !(t1_ns > t0_ns) || samples_.front().t_ns > t0_ns ||
      SecondsBetween(samples_.back().t_ns, t1_ns) > max_sample_gap_s) {
    return false;
  }
  // The last sample at or before t0 (binary search: the buffer holds seconds of samples).
  size_t lo = 0, hi = samples_.size();
  while (hi - lo > 1) {
    const size_t mid = (lo + hi) / 2;
    (samples_[mid].t_ns <= t0_ns ? lo : hi) = mid;
  }
  int64_t t = t0_ns;
  for (size_t k = lo; k < samples_.size() && t < t1_ns; ++k) {
    const int64_t next = k + 1 < samples_.size() ? samples_[k + 1].t_ns : t1_ns;
    if (SecondsBetween(samples_[k].t_ns, next) > max_sample_gap_s) return false;
    const int64_t end = std::min(next, t1_ns);
    if (end > t) out->Integrate(samples_[k].gyro, samples_[k].acc, SecondsBetween(t, end));
    t = end;
  }
  return t >= t1_ns;
}

void ImuBuffer::DropBefore(int64_t t_ns) {
  // Keep the last sample at or before t_ns: it is held over t_ns.
  while (samples_.size() >= 2 && samples_[1].t_ns <= t_ns) samples_.pop_front();
}

std::optional<double> ImuBuffer::RestStatistic(int64_t t0_ns, int64_t t1_ns, const ImuBias& bias,
                                               double gravity_mps2, double gyro_noise_density,
                                               double acc_noise_density) const {
  const auto first = std::lower_bound(samples_.begin(), samples_.end(), t0_ns,
                                      [](const Sample& s, int64_t t) { return s.t_ns < t; });
  const auto last = std::upper_bound(samples_.begin(), samples_.end(), t1_ns,
                                     [](int64_t t, const Sample& s) { return t < s.t_ns; });
  const std::ptrdiff_t n = last - first;
  if (n < 10) return std::nullopt;
  const double dt = SecondsBetween(first->t_ns, (last - 1)->t_ns) / static_cast<double>(n - 1);
  if (!(dt > 0.0)) return std::nullopt;
  const double gyro_var = gyro_noise_density * gyro_noise_density / dt;
  const double acc_var = acc_noise_density * acc_noise_density / dt;
  Eigen::Vector3d mean_acc = Eigen::Vector3d::Zero();
  for (auto it = first; it != last; ++it) mean_acc += it->acc - bias.acc;
  if (!(mean_acc.norm() > 0.0)) return std::nullopt;
  const Eigen::Vector3d gravity = gravity_mps2 * mean_acc.normalized();
  double sum = 0.0;
  for (auto it = first; it != last; ++it) {
    sum += (it->gyro - bias.gyro).squaredNorm() / gyro_var +
           (it->acc - bias.acc - gravity).squaredNorm() / acc_var;
  }
  return sum / (6.0 * static_cast<double>(n));
}

ImuBuffer ImuBuffer::Slice(int64_t t0_ns, int64_t t1_ns) const {
  ImuBuffer out;
  for (size_t k = 0; k < samples_.size(); ++k) {
    const Sample& s = samples_[k];
    if (s.t_ns >= t1_ns) break;
    const bool held_over_t0 = k + 1 < samples_.size() && samples_[k + 1].t_ns <= t0_ns;
    if (!held_over_t0) out.samples_.push_back(s);
  }
  return out;
}

void ImuBuffer::Append(const ImuBuffer& later) {
  for (const Sample& s : later.samples_) {
    if (samples_.empty() || s.t_ns > samples_.back().t_ns) samples_.push_back(s);
  }
}

}  // namespace slslam
