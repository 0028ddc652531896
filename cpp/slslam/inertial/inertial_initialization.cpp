#include "slslam/inertial/inertial_initialization.h"

#include <cmath>

#include <Eigen/Cholesky>

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"

namespace slslam {

void InertialInitOptions::Check() const {
  CheckAboveInRange("imu.gravity_mps2", gravity_mps2, 0.0, 100.0);
  CheckAboveInRange("imu.gravity_tolerance_mps2", gravity_tolerance_mps2, 0.0, 100.0);
  CheckAboveInRange("imu.acc_bias_prior_mps2", acc_bias_prior_mps2, 0.0, 100.0);
  CheckAboveInRange("imu.gyro_bias_prior_radps", gyro_bias_prior_radps, 0.0, 100.0);
  CheckAboveInRange("imu.pose_sigma_m", pose_sigma_m, 0.0, 100.0);
  CheckAboveInRange("imu.pose_sigma_rad", pose_sigma_rad, 0.0, 10.0);
  CheckAboveInRange("imu.max_rotation_residual_rad", max_rotation_residual_rad, 0.0, 10.0);
}

namespace {

// Step (1): the gyroscope bias aligning the increments' rotations with the poses'.
Eigen::Vector3d GyroBias(const std::vector<Rigid3d>& world_from_body,
                         const std::vector<ImuPreintegration>& pre, double prior_sigma,
                         double pose_sigma_rad, double* rms) {
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
  const double prior_w = 1.0 / (prior_sigma * prior_sigma);
  for (int iteration = 0; iteration < 5; ++iteration) {
    Eigen::Matrix3d H = prior_w * Eigen::Matrix3d::Identity();
    Eigen::Vector3d b = -prior_w * bg;
    double squared = 0.0;
    for (size_t k = 0; k < pre.size(); ++k) {
      ImuBias bias;
      bias.gyro = bg;
      const Eigen::Matrix3d relative =
          world_from_body[k].rotation.transpose() * world_from_body[k + 1].rotation;
      const Eigen::Vector3d r =
          LogSO3(Eigen::Quaterniond(pre[k].CorrectedDeltaR(bias).transpose() * relative));
      // r(bg + d) ~= r - J d with J the rotation increment's bias Jacobian.
      const Eigen::Matrix3d& J = pre[k].dR_dbg();
      // Weighted by the two poses' rotation noise and the increment's own.
      const double w = 1.0 / (2.0 * pose_sigma_rad * pose_sigma_rad +
                              pre[k].covariance().block<3, 3>(0, 0).trace() / 3.0);
      H += w * J.transpose() * J;
      b += w * J.transpose() * r;
      squared += r.squaredNorm();
    }
    bg += H.ldlt().solve(b);
    *rms = std::sqrt(squared / std::max<size_t>(1, pre.size()));
  }
  return bg;
}

// Rows of the linear increment equations for unknowns [v_0 .. v_{n-1}, g (3), ba (3)], whitened.
struct LinearSystem {
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
};

// The normal equations of the position and velocity increment equations, with g = g0 + Bg y
// (y: the gravity unknowns, 3 with Bg = I, or 2 on the sphere) and the bias prior.
LinearSystem IncrementSystem(const std::vector<Rigid3d>& T,
                             const std::vector<ImuPreintegration>& pre, const Eigen::Vector3d& bg,
                             const Eigen::Vector3d& g0, const Eigen::MatrixXd& Bg,
                             const InertialInitOptions& options) {
  const int n = static_cast<int>(T.size());
  const int ng = static_cast<int>(Bg.cols());
  const int size = 3 * n + ng + 3;
  const int gi = 3 * n, ai = 3 * n + ng;
  LinearSystem sys{Eigen::MatrixXd::Zero(size, size), Eigen::VectorXd::Zero(size)};
  const double pose_var = 2.0 * options.pose_sigma_m * options.pose_sigma_m;
  for (int k = 0; k + 1 < n; ++k) {
    const ImuPreintegration& p = pre[k];
    ImuBias bias;
    bias.gyro = bg;  // acc 0: the corrected increments are then linear in ba through dX_dba
    const Eigen::Vector3d c_p = p.CorrectedDeltaP(bias), c_v = p.CorrectedDeltaV(bias);
    const Eigen::Matrix3d Rt = T[k].rotation.transpose();
    const double dt = p.dt_s();
    const double var_p = p.covariance().block<3, 3>(6, 6).trace() / 3.0 + pose_var;
    const double var_v = p.covariance().block<3, 3>(3, 3).trace() / 3.0 + 1e-8;
    for (int eq = 0; eq < 2; ++eq) {
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3, size);
      Eigen::Vector3d rhs;
      Eigen::Matrix3d A_g;
      if (eq == 0) {  // position: Rt (p_j - p_i - v_i dt - g dt^2/2) - dp_dba ba = c_p
        A.block<3, 3>(0, 3 * k) = -Rt * dt;
        A_g = -0.5 * Rt * dt * dt;
        A.block<3, 3>(0, ai) = -p.dp_dba();
        rhs = c_p - Rt * (T[k + 1].translation - T[k].translation);
      } else {  // velocity: Rt (v_j - v_i - g dt) - dv_dba ba = c_v
        A.block<3, 3>(0, 3 * k) = -Rt;
        A.block<3, 3>(0, 3 * (k + 1)) = Rt;
        A_g = -Rt * dt;
        A.block<3, 3>(0, ai) = -p.dv_dba();
        rhs = c_v;
      }
      A.block(0, gi, 3, ng) = A_g * Bg;
      rhs -= A_g * g0;
      const double w = 1.0 / (eq == 0 ? var_p : var_v);
      sys.H.noalias() += w * A.transpose() * A;
      sys.b.noalias() += w * A.transpose() * rhs;
    }
  }
  const double prior = 1.0 / (options.acc_bias_prior_mps2 * options.acc_bias_prior_mps2);
  sys.H.block<3, 3>(ai, ai) += prior * Eigen::Matrix3d::Identity();
  return sys;
}

}  // namespace

InertialInitResult InitialiseInertial(const std::vector<Rigid3d>& world_from_body,
                                      const std::vector<ImuPreintegration>& preintegrated,
                                      const InertialInitOptions& options) {
  options.Check();
  const int n = static_cast<int>(world_from_body.size());
  SLSLAM_CHECK(n >= 3 && preintegrated.size() + 1 == world_from_body.size(),
               "inertial initialisation needs n >= 3 poses and n - 1 intervals, got ", n,
               " poses and ", preintegrated.size(), " intervals");
  InertialInitResult result;
  result.bias.gyro = GyroBias(world_from_body, preintegrated, options.gyro_bias_prior_radps,
                              options.pose_sigma_rad, &result.rotation_rms_rad);
  if (!(result.rotation_rms_rad <= options.max_rotation_residual_rad)) {
    result.reason = "the IMU's rotations do not match the camera's (RMS " +
                    std::to_string(result.rotation_rms_rad) + " rad: extrinsics or time offset?)";
    return result;
  }
  const Eigen::Vector3d& bg = result.bias.gyro;
  // Step (2): everything linear, gravity free.
  LinearSystem sys = IncrementSystem(world_from_body, preintegrated, bg, Eigen::Vector3d::Zero(),
                                     Eigen::MatrixXd::Identity(3, 3), options);
  Eigen::VectorXd x = sys.H.ldlt().solve(sys.b);
  Eigen::Vector3d g = x.segment<3>(3 * n);
  result.unconstrained_gravity_mps2 = g.norm();
  if (!x.allFinite() ||
      std::abs(g.norm() - options.gravity_mps2) > options.gravity_tolerance_mps2) {
    result.reason = "the fitted gravity has magnitude " + std::to_string(g.norm()) +
                    " m/s^2, expected " + std::to_string(options.gravity_mps2) +
                    " (too little motion, or poses and IMU that disagree)";
    return result;
  }
  // Step (3): gravity on the sphere of the known magnitude.
  g = g.normalized() * options.gravity_mps2;
  for (int iteration = 0; iteration < 4; ++iteration) {
    const Eigen::Vector3d u = g.normalized();
    Eigen::Vector3d a = std::abs(u.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    Eigen::MatrixXd Bg(3, 2);
    const Eigen::Vector3d e0 = (a - a.dot(u) * u).normalized();
    Bg.col(0) = e0;
    Bg.col(1) = u.cross(e0);
    Bg *= options.gravity_mps2;
    sys = IncrementSystem(world_from_body, preintegrated, bg, g, Bg, options);
    x = sys.H.ldlt().solve(sys.b);
    if (!x.allFinite()) {
      result.reason = "the gravity refinement did not converge";
      return result;
    }
    g = (g + Bg * x.segment<2>(3 * n)).normalized() * options.gravity_mps2;
  }
  result.g_world = g;
  result.bias.acc = x.tail<3>();
  result.v_world.resize(n);
  for (int k = 0; k < n; ++k) result.v_world[k] = x.segment<3>(3 * k);
  result.success = true;
  return result;
}

}  // namespace slslam
