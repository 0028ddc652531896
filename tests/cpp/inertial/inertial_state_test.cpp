// The inertial state's propagation and camera-pose conditioning: Jacobians against finite
// differences, the propagated covariance against Monte Carlo runs of a noisy IMU, and the sample
// buffer's intervals.
#include "slslam/inertial/inertial_state.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "slslam/core/time.h"

#include "synthetic_motion.h"

namespace slslam {
namespace {

using test::SyntheticMotion;

// The error-state difference (dtheta, dp, dv, dbg, dba, dg) of `b` from `a`.
Eigen::Matrix<double, 18, 1> ErrorBetween(const InertialState& a, const InertialState& b) {
  Eigen::Matrix<double, 18, 1> e;
  e.segment<3>(0) = LogSO3(a.nav.R_world_body.conjugate() * b.nav.R_world_body);
  e.segment<3>(3) = b.nav.p_world_body - a.nav.p_world_body;
  e.segment<3>(6) = b.nav.v_world_body - a.nav.v_world_body;
  e.segment<3>(9) = b.bias.gyro - a.bias.gyro;
  e.segment<3>(12) = b.bias.acc - a.bias.acc;
  e.segment<3>(15) = b.g_world - a.g_world;
  return e;
}

InertialState Perturbed(const InertialState& s, int axis, double eps) {
  InertialState out = s;
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  d(axis % 3) = eps;
  switch (axis / 3) {
    case 0:
      out.nav.R_world_body = (s.nav.R_world_body * ExpQuaternion(d)).normalized();
      break;
    case 1:
      out.nav.p_world_body += d;
      break;
    case 2:
      out.nav.v_world_body += d;
      break;
    case 3:
      out.bias.gyro += d;
      break;
    case 4:
      out.bias.acc += d;
      break;
    default:
      out.g_world += d;
      break;
  }
  return out;
}

TEST(InertialState, PropagationJacobianMatchesFiniteDifferences) {
  const SyntheticMotion motion;
  ImuBias bias;
  bias.gyro = {0.01, -0.02, 0.005};
  bias.acc = {0.05, 0.1, -0.08};
  const ImuPreintegration pre = motion.Preintegrate(0.4, 0.9, 400.0, bias, bias);
  InertialState start;
  start.nav = motion.Nav(0.4);
  start.bias = bias;
  start.g_world = motion.g_world;
  const Matrix18d A = PropagationJacobian(start, pre);
  const InertialState end = Propagate(start, pre);
  const double eps = 1e-6;
  for (int axis = 0; axis < 18; ++axis) {
    const InertialState moved = Propagate(Perturbed(start, axis, eps), pre);
    const Eigen::Matrix<double, 18, 1> numeric = ErrorBetween(end, moved) / eps;
    EXPECT_LT((numeric - A.col(axis)).norm(), 1e-4 * std::max(1.0, A.col(axis).norm()))
        << "axis " << axis << "\nnumeric " << numeric.transpose() << "\nanalytic "
        << A.col(axis).transpose();
  }
  // The propagated state follows the true motion (noise-free samples, the bias known).
  EXPECT_LT((end.nav.p_world_body - motion.Position(0.9)).norm(), 1e-3);
  EXPECT_LT((end.nav.v_world_body - motion.Velocity(0.9)).norm(), 5e-3);  // first order at 400 Hz
}

TEST(InertialState, CameraTangentJacobianMatchesFiniteDifferences) {
  const SyntheticMotion motion;
  const NavState nav = motion.Nav(1.3);
  const Rigid3d body_from_cam(ExpSO3(Eigen::Vector3d(1.5, -0.1, 0.2)),
                              Eigen::Vector3d(0.05, -0.02, 0.1));
  const Matrix6d G = CamTangentFromBodyError(nav, body_from_cam);
  const Rigid3d cam = CamFromWorld(nav, body_from_cam);
  const double eps = 1e-7;
  for (int axis = 0; axis < 6; ++axis) {
    InertialState s;
    s.nav = nav;
    const Rigid3d moved = CamFromWorld(Perturbed(s, axis, eps).nav, body_from_cam);
    const Eigen::Matrix3d dR = moved.rotation * cam.rotation.transpose();
    Vector6d tangent;
    tangent.tail<3>() = LogSO3(Eigen::Quaterniond(dR));
    tangent.head<3>() = moved.translation - dR * cam.translation;
    EXPECT_LT((tangent / eps - G.col(axis)).norm(), 1e-5 * std::max(1.0, G.col(axis).norm()))
        << "axis " << axis;
  }
  EXPECT_GT(std::abs(G.determinant()), 1e-6);
}

TEST(InertialState, CovarianceMatchesMonteCarloOfANoisyImu) {
  // 1 s of a moving body at 200 Hz with white noise at 50x EuRoC's densities: the spread of the
  // integrated end states matches the propagated covariance (rotation, position, velocity).
  const SyntheticMotion motion;
  ImuNoiseOptions noise;
  noise.gyro_noise_density *= 50.0;
  noise.acc_noise_density *= 50.0;
  noise.gyro_random_walk = 0.0;
  noise.acc_random_walk = 0.0;
  InertialState start;
  start.nav = motion.Nav(0.0);
  start.g_world = motion.g_world;
  const ImuPreintegration clean = motion.Preintegrate(0.0, 1.0, 200.0, {}, {}, noise);
  const InertialState mean = Propagate(start, clean);
  std::mt19937 rng(7);
  std::normal_distribution<double> unit(0.0, 1.0);
  const int trials = 400;
  const double dt = 1.0 / 200.0;
  Eigen::Matrix<double, 9, 9> sample = Eigen::Matrix<double, 9, 9>::Zero();
  for (int trial = 0; trial < trials; ++trial) {
    ImuPreintegration pre({}, noise);
    for (int k = 0; k < 200; ++k) {
      const double t = (k + 0.5) * dt;
      Eigen::Vector3d wn, an;
      for (int i = 0; i < 3; ++i) {
        wn(i) = unit(rng) * noise.gyro_noise_density / std::sqrt(dt);
        an(i) = unit(rng) * noise.acc_noise_density / std::sqrt(dt);
      }
      pre.Integrate(motion.Gyro(t) + wn, motion.Accelerometer(t) + an, dt);
    }
    const Eigen::Matrix<double, 9, 1> e = ErrorBetween(mean, Propagate(start, pre)).head<9>();
    sample += e * e.transpose() / trials;
  }
  for (int block = 0; block < 3; ++block) {
    const double predicted = mean.covariance.block<3, 3>(3 * block, 3 * block).trace();
    const double measured = sample.block<3, 3>(3 * block, 3 * block).trace();
    EXPECT_NEAR(measured / predicted, 1.0, 0.2) << "block " << block;
  }
  EXPECT_NEAR(mean.PositionSigma(), std::sqrt(mean.covariance.block<3, 3>(3, 3).trace()), 1e-12);
}

TEST(InertialState, ACameraPoseCorrectsTheVelocityThroughTheCrossCovariance) {
  const SyntheticMotion motion;
  const Rigid3d body_from_cam(ExpSO3(Eigen::Vector3d(-1.2, 0.0, 0.3)),
                              Eigen::Vector3d(0.1, 0.0, -0.05));
  InertialState start;
  start.nav = motion.Nav(1.0);
  start.nav.v_world_body += Eigen::Vector3d(0.3, -0.2, 0.1);  // a velocity 0.39 m/s off
  start.g_world = motion.g_world;
  start.covariance.diagonal() << Eigen::Vector3d::Constant(1e-6), Eigen::Vector3d::Constant(1e-6),
      Eigen::Vector3d::Constant(0.25), Eigen::Vector3d::Constant(1e-6),
      Eigen::Vector3d::Constant(1e-4), Eigen::Vector3d::Constant(1e-6);
  const ImuPreintegration pre = motion.Preintegrate(1.0, 1.5, 200.0, {});
  InertialState state = Propagate(start, pre);
  const double error_before = (state.nav.v_world_body - motion.Velocity(1.5)).norm();
  const Rigid3d truth = CamFromWorld(motion.Nav(1.5), body_from_cam);
  Matrix6d information = 1e8 * Matrix6d::Identity();
  ASSERT_TRUE(ConditionOnCameraPose(truth, information, body_from_cam, &state));
  EXPECT_LT((state.nav.p_world_body - motion.Position(1.5)).norm(), 1e-6);
  const double error_after = (state.nav.v_world_body - motion.Velocity(1.5)).norm();
  EXPECT_GT(error_before, 0.3);
  EXPECT_LT(error_after, 0.1 * error_before);
  EXPECT_LT(state.PositionSigma(), 1e-3);
  // The prior it gives the pose optimiser is the inverse of the pose block's covariance.
  const Matrix6d prior = CameraPosePriorInformation(state, body_from_cam);
  EXPECT_TRUE(prior.allFinite());
  EXPECT_GT(prior.diagonal().minCoeff(), 1e5);
  // An information that is not positive definite changes nothing.
  const InertialState kept = state;
  EXPECT_FALSE(ConditionOnCameraPose(truth, Matrix6d::Zero(), body_from_cam, &state));
  EXPECT_EQ(state.nav.v_world_body, kept.nav.v_world_body);
}

// The non-holonomic constraint (no body velocity across the body's x axis): with only the velocity
// uncertain the update takes the sideways velocity out; with only the heading uncertain it turns
// the body into the velocity instead (the rotation Jacobian's sign), leaving the velocity as it is.
TEST(InertialState, ABodyVelocityConstraintMovesWhatIsUncertain) {
  InertialState state;
  state.nav.R_world_body = Eigen::Quaterniond::Identity();
  state.nav.v_world_body = {1.0, 0.05, -0.02};
  state.g_world = test::TestGravity();
  Eigen::Matrix<double, 2, 3> across;
  across << 0, 1, 0, 0, 0, 1;
  const double sigma = 1e-3;

  InertialState velocity_only = state;
  velocity_only.covariance = 1e-12 * Matrix18d::Identity();
  velocity_only.covariance.block<3, 3>(6, 6) = 0.1 * Eigen::Matrix3d::Identity();
  ASSERT_TRUE(ConditionOnBodyVelocity(across, sigma, &velocity_only));
  EXPECT_NEAR(velocity_only.nav.v_world_body.x(), 1.0, 1e-9);
  EXPECT_LT(velocity_only.nav.v_world_body.tail<2>().norm(), 1e-4);
  EXPECT_LT(velocity_only.covariance(7, 7), 2.0 * sigma * sigma);
  EXPECT_NEAR(velocity_only.covariance(6, 6), 0.1, 1e-9);  // along the axis: untouched
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix18d>(velocity_only.covariance).eigenvalues()(0),
            -1e-15);

  InertialState heading_only = state;
  heading_only.covariance = 1e-12 * Matrix18d::Identity();
  heading_only.covariance.block<3, 3>(0, 0) = 0.01 * Eigen::Matrix3d::Identity();
  ASSERT_TRUE(ConditionOnBodyVelocity(across, sigma, &heading_only));
  const Eigen::Vector3d v_body =
      heading_only.nav.R_world_body.toRotationMatrix().transpose() * heading_only.nav.v_world_body;
  EXPECT_LT(v_body.tail<2>().norm(), 2e-3) << v_body.transpose();  // (one linearised step)
  EXPECT_LT((heading_only.nav.v_world_body - state.nav.v_world_body).norm(), 1e-6);

  EXPECT_FALSE(ConditionOnBodyVelocity(across, 0.0, &heading_only));
}

// A measured body velocity: with the velocity uncertain the state takes it (the body turned, so
// the measurement is in the body frame), an outlier beyond the gate changes nothing, and a
// covariance that is not positive definite is refused.
TEST(InertialState, AMeasuredBodyVelocityIsTakenInTheBodyFrameWithinItsGate) {
  InertialState state;
  state.nav.R_world_body =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitZ()));
  state.nav.v_world_body = {0.0, 0.9, 0.0};
  state.g_world = test::TestGravity();
  state.covariance = 1e-12 * Matrix18d::Identity();
  state.covariance.block<3, 3>(6, 6) = 0.01 * Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d covariance = 1e-6 * Eigen::Matrix3d::Identity();
  InertialState taken = state;
  const Eigen::Matrix3d all = Eigen::Matrix3d::Identity();
  ASSERT_TRUE(ConditionOnMeasuredBodyVelocity(all, Eigen::Vector3d(1.0, 0.0, 0.0), covariance,
                                              &taken, 16.27));
  // body x is world y after the quarter turn
  EXPECT_LT((taken.nav.v_world_body - Eigen::Vector3d(0.0, 1.0, 0.0)).norm(), 1e-3)
      << taken.nav.v_world_body.transpose();
  EXPECT_LT(taken.covariance(7, 7), 2e-6);
  InertialState refused = state;
  EXPECT_FALSE(ConditionOnMeasuredBodyVelocity(all, Eigen::Vector3d(3.0, 0.0, 0.0), covariance,
                                               &refused, 16.27));
  EXPECT_EQ(refused.nav.v_world_body, state.nav.v_world_body);
  EXPECT_FALSE(ConditionOnMeasuredBodyVelocity(all, Eigen::Vector3d(1.0, 0.0, 0.0),
                                               Eigen::Matrix3d::Zero(), &refused));
  // One component: along body y (world -x) measured 0.2 m/s, the others left as they were.
  InertialState one = state;
  Eigen::Matrix<double, 1, 3> along_y(0.0, 1.0, 0.0);
  ASSERT_TRUE(ConditionOnMeasuredBodyVelocity(along_y, Eigen::VectorXd::Constant(1, 0.2),
                                              Eigen::MatrixXd::Constant(1, 1, 1e-6), &one));
  EXPECT_NEAR(one.nav.v_world_body.x(), -0.2, 1e-3);
  EXPECT_NEAR(one.nav.v_world_body.y(), 0.9, 1e-9);
}

// The rest statistic: about 1 for samples of white noise at the stated densities about gravity
// (with a bias that is given), far above in motion; nullopt with too few samples.
TEST(ImuBuffer, TheRestStatisticIsAboutOneAtRestAndLargeInMotion) {
  const double gyro_density = 1.7e-4, acc_density = 2e-3, dt = 0.005;
  std::mt19937 rng(3);
  std::normal_distribution<double> unit(0.0, 1.0);
  ImuBias bias;
  bias.gyro = {0.01, -0.02, 0.005};
  bias.acc = {0.1, 0.0, -0.05};
  const Eigen::Vector3d f_rest(0.0, 0.0, 9.81);
  ImuBuffer rest, moving;
  for (int k = 0; k < 200; ++k) {
    Eigen::Vector3d wn, an;
    for (int i = 0; i < 3; ++i) {
      wn(i) = unit(rng) * gyro_density / std::sqrt(dt);
      an(i) = unit(rng) * acc_density / std::sqrt(dt);
    }
    const int64_t t = NsFromSeconds(k * dt);
    rest.Add(t, bias.gyro + wn, f_rest + bias.acc + an);
    // 3 Hz vibration of 3 mm (about 1 m/s^2) and a slow turn
    const Eigen::Vector3d vib(0.0, 0.0, 1.07 * std::sin(2.0 * M_PI * 3.0 * k * dt));
    moving.Add(t, bias.gyro + Eigen::Vector3d(0, 0, 0.05) + wn, f_rest + vib + bias.acc + an);
  }
  const int64_t t1 = NsFromSeconds(199 * dt);
  const auto at_rest = rest.RestStatistic(0, t1, bias, 9.81, gyro_density, acc_density);
  ASSERT_TRUE(at_rest.has_value());
  EXPECT_NEAR(*at_rest, 1.0, 0.2);
  const auto in_motion = moving.RestStatistic(0, t1, bias, 9.81, gyro_density, acc_density);
  ASSERT_TRUE(in_motion.has_value());
  EXPECT_GT(*in_motion, 20.0);
  EXPECT_FALSE(rest.RestStatistic(0, NsFromSeconds(0.02), bias, 9.81, gyro_density, acc_density)
                   .has_value());
}

TEST(ImuBuffer, PreintegratesPartialIntervalsAndRefusesGaps) {
  ImuBuffer buffer;
  ImuPreintegration direct;
  for (int k = 0; k <= 100; ++k) {
    const double t = 0.01 * k;
    const Eigen::Vector3d w(0.1, 0.2 * k / 100.0, -0.1), a(0.5, 9.81, -0.2 * k / 100.0);
    buffer.Add(NsFromSeconds(t), w, a);
    if (t >= 0.2 - 1e-12 && t < 0.7 - 1e-12) direct.Integrate(w, a, 0.01);
  }
  ImuPreintegration from_buffer;
  ASSERT_TRUE(buffer.Preintegrate(NsFromSeconds(0.2), NsFromSeconds(0.7), 0.05, &from_buffer));
  EXPECT_NEAR(from_buffer.dt_s(), 0.5, 1e-12);
  EXPECT_LT((from_buffer.delta_p() - direct.delta_p()).norm(), 1e-9);
  ImuPreintegration partial;
  ASSERT_TRUE(buffer.Preintegrate(NsFromSeconds(0.205), NsFromSeconds(0.3), 0.05, &partial));
  EXPECT_NEAR(partial.dt_s(), 0.095, 1e-12);
  ImuPreintegration refused;
  EXPECT_FALSE(buffer.Preintegrate(NsFromSeconds(-0.1), NsFromSeconds(0.3), 0.05,
                                   &refused));  // before the first sample
  EXPECT_FALSE(buffer.Preintegrate(NsFromSeconds(0.9), NsFromSeconds(1.2), 0.05,
                                   &refused));  // past the last one
  EXPECT_FALSE(buffer.Preintegrate(NsFromSeconds(0.2), NsFromSeconds(0.7), 0.005,
                                   &refused));  // samples 10 ms apart
  EXPECT_THROW(buffer.Add(NsFromSeconds(0.5), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()),
               std::invalid_argument);
  buffer.DropBefore(NsFromSeconds(0.5));
  EXPECT_FALSE(buffer.Preintegrate(NsFromSeconds(0.2), NsFromSeconds(0.7), 0.05, &refused));
  EXPECT_TRUE(buffer.Preintegrate(NsFromSeconds(0.5), NsFromSeconds(0.7), 0.05, &refused));
}

// A keyframe's samples (Slice) integrate like the whole buffer over its interval, and two
// consecutive keyframes' slices joined (Append, as culling the middle one does) like the buffer
// over both.
TEST(ImuBuffer, SlicesIntegrateAsTheBufferAndJoinAcrossAKeyframe) {
  ImuBuffer buffer;
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.005 * k + 0.001;
    buffer.Add(NsFromSeconds(t), Eigen::Vector3d(0.1, 0.3 * std::sin(t), -0.1),
               Eigen::Vector3d(0.5 * std::cos(t), 9.81, -0.2 * t));
  }
  const auto integrated = [](const ImuBuffer& b, double t0, double t1) {
    ImuPreintegration pre;
    EXPECT_TRUE(b.Preintegrate(NsFromSeconds(t0), NsFromSeconds(t1), 0.05, &pre))
        << t0 << " " << t1;
    return pre;
  };
  const ImuBuffer first = buffer.Slice(NsFromSeconds(0.2031), NsFromSeconds(0.4502));
  const ImuBuffer second = buffer.Slice(NsFromSeconds(0.4502), NsFromSeconds(0.8007));
  EXPECT_LT(first.size(), buffer.size());
  const ImuPreintegration whole = integrated(buffer, 0.2031, 0.4502);
  const ImuPreintegration sliced = integrated(first, 0.2031, 0.4502);
  EXPECT_EQ(sliced.delta_p(), whole.delta_p());
  EXPECT_EQ(sliced.delta_R(), whole.delta_R());
  ImuBuffer joined = first;
  joined.Append(second);
  const ImuPreintegration both = integrated(buffer, 0.2031, 0.8007);
  const ImuPreintegration from_joined = integrated(joined, 0.2031, 0.8007);
  EXPECT_EQ(from_joined.delta_p(), both.delta_p());
  EXPECT_EQ(from_joined.delta_v(), both.delta_v());
  EXPECT_EQ(from_joined.covariance(), both.covariance());
}

// Times are int64 ns: on a Unix clock (1.6e18 ns) the intervals are those of the same samples
// near zero, bit for bit (float seconds there resolve 0.2 us and each interval would differ).
TEST(ImuBuffer, IntegratesTheSameAtAnEpochClock) {
  constexpr int64_t kEpochNs = 1'600'000'000'123'456'789;
  ImuBuffer near_zero, at_epoch;
  for (int k = 0; k <= 100; ++k) {
    const int64_t t_ns = 2'500'000 * k + 1'234;  // 400 Hz
    const Eigen::Vector3d w(0.1, 0.2 * std::sin(0.1 * k), -0.1), a(0.5, 9.81, 0.01 * k);
    near_zero.Add(t_ns, w, a);
    at_epoch.Add(kEpochNs + t_ns, w, a);
  }
  ImuPreintegration a, b;
  ASSERT_TRUE(near_zero.Preintegrate(10'001'000, 210'000'017, 0.05, &a));
  ASSERT_TRUE(at_epoch.Preintegrate(kEpochNs + 10'001'000, kEpochNs + 210'000'017, 0.05, &b));
  EXPECT_EQ(a.dt_s(), b.dt_s());
  EXPECT_NEAR(a.dt_s(), 0.199'999'017, 1e-15);
  EXPECT_EQ(a.delta_p(), b.delta_p());
  EXPECT_EQ(a.delta_R(), b.delta_R());
  EXPECT_EQ(a.covariance(), b.covariance());
}

}  // namespace
}  // namespace slslam
