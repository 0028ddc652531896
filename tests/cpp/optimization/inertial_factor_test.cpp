// The IMU factor between two keyframes' camera poses, velocities and biases: zero on the truth,
// its Jacobians (through PoseManifold, as Ceres sees them) against central differences, and a
// visual-inertial bundle adjustment that recovers velocities and biases from exact poses.
#include "slslam/optimization/inertial_factor.h"

#include <vector>

#include <ceres/autodiff_cost_function.h>
#include <gtest/gtest.h>

#include "../inertial/synthetic_motion.h"
#include "../test_support.h"
#include "check_cost.h"
#include "slslam/geometry/rotation.h"
#include "slslam/optimization/bundle_adjustment.h"
#include "slslam/optimization/sqrt_information.h"

namespace slslam {
namespace {

// The camera 10 cm ahead of the IMU, turned (Kalibr-like extrinsics).
Rigid3d BodyFromCam() {
  return Rigid3d(ExpSO3(Eigen::Vector3d(1.2, -0.3, 0.4)), Eigen::Vector3d(0.1, -0.02, 0.05));
}

std::vector<double> PoseParams(const test::SyntheticMotion& motion, double t) {
  std::vector<double> p(kPoseSize);
  const Rigid3d cam_from_world = (motion.WorldFromBody(t) * BodyFromCam()).Inverse();
  PoseToParameters(cam_from_world, p.data());
  return p;
}

std::vector<double> SpeedBias(const Eigen::Vector3d& v, const ImuBias& bias) {
  return {v.x(),         v.y(),        v.z(),        bias.gyro.x(), bias.gyro.y(),
          bias.gyro.z(), bias.acc.x(), bias.acc.y(), bias.acc.z()};
}

TEST(CameraImuFactor, VanishesOnTheTrueMotion) {
  const test::SyntheticMotion motion;
  ImuBias bias;
  bias.gyro = Eigen::Vector3d(0.01, -0.02, 0.005);
  bias.acc = Eigen::Vector3d(0.05, 0.02, -0.03);
  const double t0 = 1.0, t1 = 1.5;
  // Integrated at the true bias: the residual is the integration error alone.
  const ImuPreintegration pre = motion.Preintegrate(t0, t1, 2000.0, bias, bias);
  const CameraImuFactor factor(pre, motion.g_world, BodyFromCam());
  const std::vector<double> pi = PoseParams(motion, t0), pj = PoseParams(motion, t1);
  const std::vector<double> vbi = SpeedBias(motion.Velocity(t0), bias);
  const std::vector<double> vbj = SpeedBias(motion.Velocity(t1), bias);
  const double gravity[kGravitySize] = {0.0, 0.0};
  const double* parameters[5] = {pi.data(), vbi.data(), pj.data(), vbj.data(), gravity};
  Eigen::Matrix<double, 15, 1> whitened;
  ASSERT_TRUE(factor.Evaluate(parameters, whitened.data(), nullptr));
  // Back to units (rad, m/s, m): within the integration's first-order error at 2 kHz (each
  // sample's specific force rotated by the increment at its start: about w dt |a| T / 2 =
  // 0.6 rad/s * 0.5 ms * 10 m/s^2 * 0.5 s / 2 ~ 1e-3 m/s; a wrong lever arm, gravity or frame
  // is off by metres per second).
  const Matrix15d sqrt_information = ImuIntervalSqrtInformation(pre);
  const Eigen::Matrix<double, 15, 1> r = sqrt_information.fullPivLu().solve(whitened);
  ASSERT_TRUE(r.allFinite());
  EXPECT_LT(r.head<3>().norm(), 1e-6);
  EXPECT_LT(r.segment<3>(3).norm(), 2e-3);
  EXPECT_LT(r.segment<3>(6).norm(), 5e-4);
  EXPECT_LT(r.tail<6>().norm(), 1e-12);
}

TEST(CameraImuFactor, JacobiansThroughThePoseManifoldMatchCentralDifferences) {
  const test::SyntheticMotion motion;
  ImuBias bias_hat;
  bias_hat.gyro = Eigen::Vector3d(0.01, -0.02, 0.005);
  const ImuPreintegration pre = motion.Preintegrate(0.3, 0.8, 400.0, ImuBias{}, bias_hat);
  const CameraImuFactor factor(pre, motion.g_world, BodyFromCam());
  // Away from the truth, so that every residual block is non-zero.
  std::vector<std::vector<double>> params = {
      PoseParams(motion, 0.3),
      SpeedBias(motion.Velocity(0.3) + Eigen::Vector3d(0.1, 0, -0.2), bias_hat),
      PoseParams(motion, 0.85), SpeedBias(motion.Velocity(0.8), ImuBias{})};
  params[3][3] = 0.02;
  params[3][8] = -0.1;
  params.push_back({0.01, -0.02});  // gravity's direction turned a little
  const PoseManifold pose_manifold;
  {
    std::vector<const double*> ptrs;
    for (auto& p : params) ptrs.push_back(p.data());
    Eigen::Matrix<double, 15, 1> residual;
    ASSERT_TRUE(factor.Evaluate(ptrs.data(), residual.data(), nullptr));
    EXPECT_GT(residual.norm(), 1.0);
  }
  test::CheckCost(factor, params, {&pose_manifold, nullptr, &pose_manifold, nullptr, nullptr});
}

constexpr int kChainKeyframes = 9;
double ChainTime(int k) { return 1.0 + 0.25 * k; }

// Nine keyframes every 0.25 s from t = 1 s along the motion with exact poses (held), their
// velocities the truth's (or zero with `velocities_from_zero`), biases zero, and
// the IMU between consecutive ones read with `bias` and integrated at a zero bias (the factor's
// first-order bias correction carries the rest), under gravity `g_world`.
BaProblem ImuChain(const test::SyntheticMotion& motion, const ImuBias& bias,
                   bool velocities_from_zero, const Eigen::Vector3d& g_world) {
  BaProblem problem;
  problem.inertial.body_from_cam = BodyFromCam();
  problem.inertial.g_world = g_world;
  for (int k = 0; k < kChainKeyframes; ++k) {
    const double t = ChainTime(k);
    problem.poses.push_back({(motion.WorldFromBody(t) * BodyFromCam()).Inverse(), true});
    const Eigen::Vector3d v = velocities_from_zero ? Eigen::Vector3d::Zero() : motion.Velocity(t);
    problem.inertial.states.push_back({v, ImuBias{}, false});
    if (k == 0) continue;
    BaInertialFactor f;
    f.pose_i = f.state_i = k - 1;
    f.pose_j = f.state_j = k;
    f.pre = motion.Preintegrate(ChainTime(k - 1), t, 400.0, bias, ImuBias{});
    problem.inertial.factors.push_back(f);
  }
  return problem;
}

BundleAdjustmentReport SolveChain(BaProblem* problem) {
  BundleAdjustmentOptions options;
  options.robust_iterations = 20;
  options.refine_iterations = 20;
  return SolveBundleAdjustment(test::EurocLikeRig(), problem, options);
}

// The IMU read with a bias: bundle adjustment with the IMU factors alone recovers every velocity
// and the biases from zero-velocity, zero-bias starts.
TEST(InertialBundleAdjustment, RecoversVelocitiesAndBiasesFromExactPoses) {
  const test::SyntheticMotion motion;
  ImuBias bias;
  bias.gyro = Eigen::Vector3d(0.004, -0.003, 0.002);
  bias.acc = Eigen::Vector3d(0.08, -0.05, 0.06);
  BaProblem problem = ImuChain(motion, bias, /*velocities_from_zero=*/true, motion.g_world);
  ASSERT_TRUE(SolveChain(&problem).solved);
  for (int k = 0; k < kChainKeyframes; ++k) {
    EXPECT_LT((problem.inertial.states[k].v_world_body - motion.Velocity(ChainTime(k))).norm(),
              0.01)
        << "keyframe " << k;
    EXPECT_LT((problem.inertial.states[k].bias.gyro - bias.gyro).norm(), 5e-4) << k;
    EXPECT_LT((problem.inertial.states[k].bias.acc - bias.acc).norm(), 0.02) << k;
  }
}

// The same with gravity's direction about 1 degree off at the start and estimated (a loose prior):
// the solve turns it back within 0.05 degrees.
TEST(InertialBundleAdjustment, EstimatesGravitysDirectionFromATiltedStart) {
  const test::SyntheticMotion motion;
  BaProblem problem = ImuChain(
      motion, ImuBias{}, /*velocities_from_zero=*/false,
      ExpSO3(Eigen::Vector3d(1.0, 0.5, 0.0).normalized() * (M_PI / 180.0)) * motion.g_world);
  problem.inertial.gravity_sigma_rad = 0.1;
  const double before =
      std::acos(problem.inertial.g_world.normalized().dot(motion.g_world.normalized()));
  ASSERT_TRUE(SolveChain(&problem).solved);
  const double after = std::acos(
      std::min(1.0, problem.inertial.g_world.normalized().dot(motion.g_world.normalized())));
  EXPECT_GT(before, 0.9 * M_PI / 180.0);  // (the axis is not quite across gravity)
  EXPECT_LT(after, 0.05 * M_PI / 180.0);
  EXPECT_NEAR(problem.inertial.g_world.norm(), motion.g_world.norm(), 1e-9);
}

// The LiDAR smoother's IMU factor as it was before it shared ImuIntervalResidual (kept verbatim as
// the reference): the shared residual must give the same numbers bit for bit, values and
// automatic derivatives, so the smoother's trajectories stay byte-identical.
struct ReferenceLioImuFactor {
  ReferenceLioImuFactor(const ImuPreintegration& imu, const Matrix15d& sqrt_info)
      : imu(imu), sqrt_info(sqrt_info) {}

  template <typename T>
  bool operator()(const T* qi_, const T* pi_, const T* vbi_, const T* qj_, const T* pj_,
                  const T* vbj_, T* out) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> qi(qi_), qj(qj_);
    const Eigen::Map<const V3> pi(pi_), pj(pj_), vi(vbi_), bgi(vbi_ + 3), bai(vbi_ + 6);
    const Eigen::Map<const V3> vj(vbj_), bgj(vbj_ + 3), baj(vbj_ + 6);
    const V3 dbg = bgi - imu.bias_hat().gyro.cast<T>();
    const V3 dba = bai - imu.bias_hat().acc.cast<T>();
    const V3 dtheta = imu.dR_dbg().cast<T>() * dbg;
    Eigen::Quaternion<T> q_corr;
    T aa[3] = {dtheta(0), dtheta(1), dtheta(2)}, qc[4];
    ceres::AngleAxisToQuaternion(aa, qc);
    q_corr = Eigen::Quaternion<T>(qc[0], qc[1], qc[2], qc[3]);
    const Eigen::Quaternion<T> dq = Eigen::Quaterniond(imu.delta_R()).cast<T>() * q_corr;
    const Eigen::Quaternion<T> err = dq.conjugate() * qi.conjugate() * qj;
    T qe[4] = {err.w(), err.x(), err.y(), err.z()}, re[3];
    ceres::QuaternionToAngleAxis(qe, re);
    const double dt = imu.dt_s();
    const V3 g = imu.gravity_world().cast<T>();
    const Eigen::Matrix<T, 3, 3> Rit = qi.conjugate().toRotationMatrix();
    const V3 dv =
        imu.delta_v().cast<T>() + imu.dv_dbg().cast<T>() * dbg + imu.dv_dba().cast<T>() * dba;
    const V3 dp =
        imu.delta_p().cast<T>() + imu.dp_dbg().cast<T>() * dbg + imu.dp_dba().cast<T>() * dba;
    Eigen::Matrix<T, 15, 1> r;
    r.template segment<3>(0) = V3(re[0], re[1], re[2]);
    r.template segment<3>(3) = Rit * (vj - vi - g * T(dt)) - dv;
    r.template segment<3>(6) = Rit * (pj - pi - vi * T(dt) - T(0.5 * dt * dt) * g) - dp;
    r.template segment<3>(9) = bgj - bgi;
    r.template segment<3>(12) = baj - bai;
    Eigen::Map<Eigen::Matrix<T, 15, 1>> residual(out);
    residual = sqrt_info.cast<T>() * r;
    return true;
  }

  ImuPreintegration imu;
  Matrix15d sqrt_info;
};

// The same through the shared residual (as lidar/lio_smoother.cpp calls it).
struct SharedLioImuFactor {
  SharedLioImuFactor(const ImuPreintegration& imu, const Matrix15d& sqrt_info)
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

TEST(ImuIntervalResidual, IsTheLidarSmoothersFormerFactorBitForBit) {
  const test::SyntheticMotion motion;
  ImuBias bias_hat;
  bias_hat.gyro = Eigen::Vector3d(0.003, -0.001, 0.002);
  bias_hat.acc = Eigen::Vector3d(0.02, 0.01, -0.03);
  const ImuPreintegration pre = motion.Preintegrate(0.2, 0.3, 400.0, ImuBias{}, bias_hat);
  // The former smoother's square root of the information, from its own noise (the same values).
  Matrix15d cov = Matrix15d::Zero();
  cov.topLeftCorner<9, 9>() = pre.covariance();
  const ImuNoiseOptions noise;
  cov.block<3, 3>(9, 9).diagonal().setConstant(noise.gyro_random_walk * noise.gyro_random_walk *
                                               pre.dt_s());
  cov.block<3, 3>(12, 12).diagonal().setConstant(noise.acc_random_walk * noise.acc_random_walk *
                                                 pre.dt_s());
  cov.diagonal() = cov.diagonal().cwiseMax(1e-12);
  const Matrix15d former = SqrtInformation<15>(Matrix15d(cov.inverse()));
  EXPECT_EQ(ImuIntervalSqrtInformation(pre), former);
  const Eigen::Quaterniond qi = Eigen::Quaterniond(motion.Attitude(0.2)).normalized();
  const Eigen::Quaterniond qj =
      Eigen::Quaterniond(motion.Attitude(0.3) * ExpSO3(Eigen::Vector3d(0.01, 0, -0.02)))
          .normalized();
  Eigen::Vector3d pi = motion.Position(0.2),
                  pj = motion.Position(0.3) + Eigen::Vector3d(0.01, 0, 0);
  std::vector<double> vbi = SpeedBias(motion.Velocity(0.2), bias_hat);
  std::vector<double> vbj = SpeedBias(motion.Velocity(0.3), ImuBias{});
  vbi[4] += 0.001;
  vbi[7] -= 0.02;
  const double* parameters[6] = {qi.coeffs().data(), pi.data(), vbi.data(),
                                 qj.coeffs().data(), pj.data(), vbj.data()};
  const ceres::AutoDiffCostFunction<ReferenceLioImuFactor, 15, 4, 3, 9, 4, 3, 9> reference(
      new ReferenceLioImuFactor(pre, former));
  const ceres::AutoDiffCostFunction<SharedLioImuFactor, 15, 4, 3, 9, 4, 3, 9> shared(
      new SharedLioImuFactor(pre, former));
  const int sizes[6] = {4, 3, 9, 4, 3, 9};
  std::vector<std::vector<double>> j_ref(6), j_new(6);
  double* ref_ptrs[6];
  double* new_ptrs[6];
  for (int b = 0; b < 6; ++b) {
    j_ref[b].assign(15 * sizes[b], 0.0);
    j_new[b].assign(15 * sizes[b], 1.0);
    ref_ptrs[b] = j_ref[b].data();
    new_ptrs[b] = j_new[b].data();
  }
  // With Jacobians (Jets) and without (doubles: Ceres' cost evaluations), each against its own.
  Eigen::Matrix<double, 15, 1> r_ref, r_new, r_ref_plain, r_new_plain;
  ASSERT_TRUE(reference.Evaluate(parameters, r_ref.data(), ref_ptrs));
  ASSERT_TRUE(shared.Evaluate(parameters, r_new.data(), new_ptrs));
  ASSERT_TRUE(reference.Evaluate(parameters, r_ref_plain.data(), nullptr));
  ASSERT_TRUE(shared.Evaluate(parameters, r_new_plain.data(), nullptr));
  EXPECT_GT(r_ref.norm(), 1.0);
  EXPECT_EQ(r_new, r_ref);
  EXPECT_EQ(r_new_plain, r_ref_plain);
  for (int b = 0; b < 6; ++b) EXPECT_EQ(j_new[b], j_ref[b]) << "block " << b;
}

}  // namespace
}  // namespace slslam
