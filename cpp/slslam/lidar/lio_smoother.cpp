#include "slslam/lidar/lio_smoother.h"

#include <cmath>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "slslam/core/check.h"
#include "slslam/optimization/inertial_factor.h"
#include "slslam/optimization/sqrt_information.h"

namespace slslam::lidar {

void LioSmootherOptions::Check() const {
  SLSLAM_CHECK(window >= 2 && window <= 100, "LioSmootherOptions.window must be in [2, 100], got ",
               window);
  SLSLAM_CHECK(max_iterations >= 1 && max_iterations <= 100,
               "LioSmootherOptions.max_iterations must be in [1, 100], got ", max_iterations);
  SLSLAM_CHECK(
      initial_velocity_sigma_mps > 0 && initial_gyro_bias_sigma > 0 && initial_acc_bias_sigma > 0,
      "LioSmootherOptions initial sigmas must be > 0");
}

namespace {

// One preintegrated IMU interval between states i and j (optimization/inertial_factor.h) under
// the z-up world's gravity. Parameters: q_i (x, y, z, w), p_i, vb_i (v, bg, ba), q_j, p_j, vb_j.
struct ImuFactor {
  ImuFactor(const ImuPreintegration& imu, const Matrix15d& sqrt_info)
      : imu(imu), sqrt_info(sqrt_info) {}

  template <typename T>
  bool operator()(const T* qi_, const T* pi_, const T* vbi_, const T* qj_, const T* pj_,
                  const T* vbj_, T* out) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> qi(qi_), qj(qj_);
    const Eigen::Map<const V3> pi(pi_), pj(pj_);
    Eigen::Matrix<T, 15, 1> r;
    ImuIntervalResidual(imu, V3(imu.gravity_world().cast<T>()), Eigen::Quaternion<T>(qi), V3(pi),
                        vbi_, Eigen::Quaternion<T>(qj), V3(pj), vbj_, &r);
    Eigen::Map<Eigen::Matrix<T, 15, 1>> residual(out);
    residual = sqrt_info.cast<T>() * r;
    return true;
  }

  ImuPreintegration imu;
  Matrix15d sqrt_info;
};

// LiDAR pose of the sensor (body pose composed with body_from_sensor) against the scan-to-map
// pose.
struct ScanFactor {
  ScanFactor(const Rigid3d& world_from_sensor, const Rigid3d& body_from_sensor,
             const Eigen::Matrix<double, 6, 6>& sqrt_info)
      : q_meas(world_from_sensor.rotation),
        p_meas(world_from_sensor.translation),
        q_bs(body_from_sensor.rotation),
        t_bs(body_from_sensor.translation),
        sqrt_info(sqrt_info) {}

  template <typename T>
  bool operator()(const T* q_, const T* p_, T* out) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q_wb(q_);
    const Eigen::Map<const V3> p_wb(p_);
    const Eigen::Quaternion<T> q_ws = q_wb * q_bs.cast<T>();
    const V3 p_ws = p_wb + q_wb * t_bs.cast<T>();
    const Eigen::Quaternion<T> err = q_ws * q_meas.conjugate().cast<T>();
    T qe[4] = {err.w(), err.x(), err.y(), err.z()}, re[3];
    ceres::QuaternionToAngleAxis(qe, re);
    Eigen::Matrix<T, 6, 1> r;
    r.template head<3>() = p_ws - p_meas.cast<T>();
    r.template tail<3>() = V3(re[0], re[1], re[2]);
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(out);
    residual = sqrt_info.cast<T>() * r;
    return true;
  }

  Eigen::Quaterniond q_meas;
  Eigen::Vector3d p_meas;
  Eigen::Quaterniond q_bs;
  Eigen::Vector3d t_bs;
  Eigen::Matrix<double, 6, 6> sqrt_info;
};

// Prior on velocity and biases of the first state.
struct SpeedBiasPrior {
  Eigen::Matrix<double, 9, 1> mean;
  Eigen::Matrix<double, 9, 1> inv_sigma;
  template <typename T>
  bool operator()(const T* vb, T* out) const {
    for (int k = 0; k < 9; ++k) out[k] = (vb[k] - T(mean(k))) * T(inv_sigma(k));
    return true;
  }
};

// Prior on the first pose: position and yaw fix the gauge (held to 1e-4), roll and pitch only
// start from the gravity alignment (the IMU and the scans observe them).
struct FirstPosePrior {
  Eigen::Quaterniond q0;
  Eigen::Vector3d p0;
  Eigen::Matrix<double, 6, 1> inv_sigma;
  template <typename T>
  bool operator()(const T* q_, const T* p_, T* out) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_);
    const Eigen::Quaternion<T> err = q * q0.conjugate().cast<T>();  // world-frame rotation
    T qe[4] = {err.w(), err.x(), err.y(), err.z()}, re[3];
    ceres::QuaternionToAngleAxis(qe, re);
    for (int k = 0; k < 3; ++k) {
      out[k] = (p_[k] - T(p0(k))) * T(inv_sigma(k));
      out[3 + k] = re[k] * T(inv_sigma(3 + k));
    }
    return true;
  }
};

}  // namespace

struct LioSmoother::Node {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 9, 1> vb = Eigen::Matrix<double, 9, 1>::Zero();
  std::unique_ptr<ImuPreintegration> imu;  // from the previous node to this one (none: first)
  Rigid3d world_from_sensor;
  Eigen::Matrix<double, 6, 6> sqrt_info = Eigen::Matrix<double, 6, 6>::Zero();
  bool has_scan = false;
  bool first = false;  // the run's first state: it carries the speed / bias prior

  LioState State() const {
    LioState s;
    s.nav.R_world_body = q;
    s.nav.p_world_body = p;
    s.nav.v_world_body = vb.head<3>();
    s.bias.gyro = vb.segment<3>(3);
    s.bias.acc = vb.tail<3>();
    return s;
  }
};

LioSmoother::LioSmoother(const LioSmootherOptions& options, const ImuNoiseOptions& noise,
                         const Rigid3d& body_from_sensor)
    : options_(options), noise_(noise), body_from_sensor_(body_from_sensor) {
  options_.Check();
  noise_.Check();
}

LioSmoother::~LioSmoother() = default;

void LioSmoother::Initialise(const LioState& state) {
  states_.clear();
  auto node = std::make_unique<Node>();
  node->q = state.nav.R_world_body.normalized();
  node->p = state.nav.p_world_body;
  node->vb << state.nav.v_world_body, state.bias.gyro, state.bias.acc;
  node->first = true;
  first_q_ = node->q;
  first_p_ = node->p;
  states_.push_back(std::move(node));
}

const LioState& LioSmoother::newest() const {
  SLSLAM_CHECK(!states_.empty(), "LioSmoother: not initialised");
  static thread_local LioState state;
  state = states_.back()->State();
  return state;
}

void LioSmoother::Transform(const Rigid3d& new_from_old) {
  const Eigen::Quaterniond q(new_from_old.rotation);
  for (auto& node : states_) {
    node->q = (q * node->q).normalized();
    node->p = new_from_old * node->p;
    node->vb.head<3>() = q * node->vb.head<3>().eval();
    node->world_from_sensor = new_from_old * node->world_from_sensor;
  }
}

LioState LioSmoother::Update(const ImuPreintegration& imu, const Rigid3d& world_from_sensor,
                             const Eigen::Matrix<double, 6, 6>& information) {
  SLSLAM_CHECK(!states_.empty(), "LioSmoother: Update before Initialise");
  SLSLAM_CHECK(imu.dt_s() > 0, "LioSmoother: empty IMU interval");
  const LioState prev = states_.back()->State();
  auto node = std::make_unique<Node>();
  // Initial guess: the IMU prediction for velocity and biases, the LiDAR pose for the pose.
  const NavState predicted = imu.Predict(prev.nav, prev.bias);
  const Rigid3d world_from_body = world_from_sensor * body_from_sensor_.Inverse();
  node->q = Eigen::Quaterniond(world_from_body.rotation).normalized();
  node->p = world_from_body.translation;
  node->vb << predicted.v_world_body, prev.bias.gyro, prev.bias.acc;
  node->imu = std::make_unique<ImuPreintegration>(imu);
  node->world_from_sensor = world_from_sensor;
  node->sqrt_info = SqrtInformation<6>(information);
  node->has_scan = true;
  states_.push_back(std::move(node));
  while (static_cast<int>(states_.size()) > options_.window) states_.pop_front();

  ceres::Problem problem;
  for (auto& n : states_) {
    problem.AddParameterBlock(n->q.coeffs().data(), 4, new ceres::EigenQuaternionManifold);
    problem.AddParameterBlock(n->p.data(), 3);
    problem.AddParameterBlock(n->vb.data(), 9);
  }
  for (size_t k = 0; k < states_.size(); ++k) {
    Node& n = *states_[k];
    if (n.has_scan) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ScanFactor, 6, 4, 3>(new ScanFactor(
                                   n.world_from_sensor, body_from_sensor_, n.sqrt_info)),
                               nullptr, n.q.coeffs().data(), n.p.data());
    }
    if (n.first) {
      auto* pose_prior = new FirstPosePrior;
      pose_prior->q0 = first_q_;
      pose_prior->p0 = first_p_;
      pose_prior->inv_sigma << Eigen::Vector3d::Constant(1e4),
          1.0 / options_.initial_tilt_sigma_rad, 1.0 / options_.initial_tilt_sigma_rad, 1e4;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<FirstPosePrior, 6, 4, 3>(pose_prior),
                               nullptr, n.q.coeffs().data(), n.p.data());
      auto* prior = new SpeedBiasPrior;
      prior->mean = n.vb;
      prior->inv_sigma << Eigen::Vector3d::Constant(1.0 / options_.initial_velocity_sigma_mps),
          Eigen::Vector3d::Constant(1.0 / options_.initial_gyro_bias_sigma),
          Eigen::Vector3d::Constant(1.0 / options_.initial_acc_bias_sigma);
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SpeedBiasPrior, 9, 9>(prior),
                               nullptr, n.vb.data());
    }
    if (k == 0 || !n.imu) continue;
    Node& m = *states_[k - 1];
    const ImuPreintegration& pre = *n.imu;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ImuFactor, 15, 4, 3, 9, 4, 3, 9>(
                                 new ImuFactor(pre, ImuIntervalSqrtInformation(pre))),
                             nullptr, m.q.coeffs().data(), m.p.data(), m.vb.data(),
                             n.q.coeffs().data(), n.p.data(), n.vb.data());
  }
  // The oldest state is held (it fixes the gauge and summarises what left the window), except for
  // the run's first state, whose priors hold position and yaw but let tilt, velocity and biases
  // be estimated.
  Node& oldest = *states_.front();
  if (!oldest.first) {
    problem.SetParameterBlockConstant(oldest.q.coeffs().data());
    problem.SetParameterBlockConstant(oldest.p.data());
    problem.SetParameterBlockConstant(oldest.vb.data());
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;  // a chain: sparse and banded
  solver.max_num_iterations = options_.max_iterations;
  solver.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  return states_.back()->State();
}

}  // namespace slslam::lidar
