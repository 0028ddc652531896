#include "slslam/optimization/cost_functions.h"

#include "slslam/core/check.h"

namespace slslam {

namespace {

constexpr int kRowMajor = Eigen::RowMajor;

// Writes a (rows x tangent) tangent Jacobian into the first columns of a row-major
// (rows x ambient) Ceres Jacobian and zeroes the rest.
template <int Rows, int Tangent, int Ambient>
void WriteLifted(const Eigen::Matrix<double, Rows, Tangent>& tangent, double inv_sigma,
                 double* out) {
  Eigen::Map<Eigen::Matrix<double, Rows, Ambient, kRowMajor>> j(out);
  j.setZero();
  j.template leftCols<Tangent>() = inv_sigma * tangent;
}

double InverseSigma(double sigma_px) {
  SLSLAM_CHECK(std::isfinite(sigma_px) && sigma_px > 0.0,
               "measurement sigma must be positive, got ", sigma_px);
  return 1.0 / sigma_px;
}

}  // namespace

PointCost::PointCost(const PinholeCamera& camera, const Eigen::Vector2d& observed_px,
                     double sigma_px)
    : camera_(camera), observed_(observed_px), inv_sigma_(InverseSigma(sigma_px)) {}

bool PointCost::Evaluate(double const* const* parameters, double* residuals,
                         double** jacobians) const {
  Rigid3d cam_from_world;
  ParametersToPose(parameters[0], &cam_from_world);
  const Eigen::Map<const Eigen::Vector3d> point(parameters[1]);
  Eigen::Vector2d e;
  Eigen::Matrix<double, 2, 6> d_pose;
  Eigen::Matrix<double, 2, 3> d_point;
  const bool want = jacobians != nullptr;
  if (!PointResidual(camera_, cam_from_world, point, observed_, &e, want ? &d_pose : nullptr,
                     want ? &d_point : nullptr)) {
    return false;
  }
  Eigen::Map<Eigen::Vector2d> r(residuals);
  r = inv_sigma_ * e;
  if (want && jacobians[0]) WriteLifted<2, 6, kPoseSize>(d_pose, inv_sigma_, jacobians[0]);
  if (want && jacobians[1]) {
    Eigen::Map<Eigen::Matrix<double, 2, 3, kRowMajor>> j(jacobians[1]);
    j = inv_sigma_ * d_point;
  }
  return true;
}

StereoPointCost::StereoPointCost(const StereoRig& rig, const Eigen::Vector3d& observed,
                                 double sigma_px)
    : rig_(rig), observed_(observed), inv_sigma_(InverseSigma(sigma_px)) {}

bool StereoPointCost::Evaluate(double const* const* parameters, double* residuals,
                               double** jacobians) const {
  Rigid3d cam_from_world;
  ParametersToPose(parameters[0], &cam_from_world);
  const Eigen::Map<const Eigen::Vector3d> point(parameters[1]);
  Eigen::Vector3d e;
  Eigen::Matrix<double, 3, 6> d_pose;
  Eigen::Matrix<double, 3, 3> d_point;
  const bool want = jacobians != nullptr;
  if (!StereoPointResidual(rig_, cam_from_world, point, observed_, &e, want ? &d_pose : nullptr,
                           want ? &d_point : nullptr)) {
    return false;
  }
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = inv_sigma_ * e;
  if (want && jacobians[0]) WriteLifted<3, 6, kPoseSize>(d_pose, inv_sigma_, jacobians[0]);
  if (want && jacobians[1]) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, kRowMajor>> j(jacobians[1]);
    j = inv_sigma_ * d_point;
  }
  return true;
}

LineCost::LineCost(const PinholeCamera& camera, const Eigen::Vector2d& start_px,
                   const Eigen::Vector2d& end_px, double angle_weight, double sigma_px)
    : camera_(camera),
      start_(start_px),
      end_(end_px),
      angle_weight_(angle_weight),
      inv_sigma_(InverseSigma(sigma_px)) {}

bool LineCost::Evaluate(double const* const* parameters, double* residuals,
                        double** jacobians) const {
  Rigid3d cam_from_world;
  ParametersToPose(parameters[0], &cam_from_world);
  const OrthonormalLine line = ParametersToLine(parameters[1]);
  Eigen::Vector3d e;
  Eigen::Matrix<double, 3, 6> d_pose;
  Eigen::Matrix<double, 3, 6> d_plucker;
  const bool want = jacobians != nullptr;
  if (!LineResidual(camera_, cam_from_world, line.ToPlucker(), start_, end_, angle_weight_, &e,
                    want ? &d_pose : nullptr, want ? &d_plucker : nullptr)) {
    return false;
  }
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = inv_sigma_ * e;
  if (want && jacobians[0]) WriteLifted<3, 6, kPoseSize>(d_pose, inv_sigma_, jacobians[0]);
  if (want && jacobians[1]) {
    const Eigen::Matrix<double, 3, 4> d_line = d_plucker * line.PluckerJacobian();
    WriteLifted<3, 4, kLineSize>(d_line, inv_sigma_, jacobians[1]);
  }
  return true;
}

}  // namespace slslam
