#include "slslam/optimization/cost_functions.h"

#include <algorithm>
#include <cmath>

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"

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

StereoPointHalfCost::StereoPointHalfCost(const StereoRig& rig, const Eigen::Vector3d& observed,
                                         double sigma_px, int half)
    : whole_(rig, observed, sigma_px), row_(2 * half) {
  SLSLAM_CHECK(half == 0 || half == 1, "a stereo observation has halves 0 and 1, got ", half);
}

bool StereoPointHalfCost::Evaluate(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  // The whole observation's rows, then this half's: rows 0 and 1, or row 2 and a zero row.
  Eigen::Vector3d e;
  Eigen::Matrix<double, 3, kPoseSize, kRowMajor> d_pose;
  Eigen::Matrix<double, 3, 3, kRowMajor> d_point;
  double* whole_jacobians[2] = {jacobians && jacobians[0] ? d_pose.data() : nullptr,
                                jacobians && jacobians[1] ? d_point.data() : nullptr};
  if (!whole_.Evaluate(parameters, e.data(), jacobians ? whole_jacobians : nullptr)) return false;
  const bool two = row_ == 0;
  residuals[0] = e(row_);
  residuals[1] = two ? e(1) : 0.0;
  if (jacobians && jacobians[0]) {
    Eigen::Map<Eigen::Matrix<double, 2, kPoseSize, kRowMajor>> j(jacobians[0]);
    j.row(0) = d_pose.row(row_);
    if (two) {
      j.row(1) = d_pose.row(1);
    } else {
      j.row(1).setZero();
    }
  }
  if (jacobians && jacobians[1]) {
    Eigen::Map<Eigen::Matrix<double, 2, 3, kRowMajor>> j(jacobians[1]);
    j.row(0) = d_point.row(row_);
    if (two) {
      j.row(1) = d_point.row(1);
    } else {
      j.row(1).setZero();
    }
  }
  return true;
}

LineCost::LineCost(const PinholeCamera& camera, const Eigen::Vector2d& start_px,
                   const Eigen::Vector2d& end_px, double angle_weight, double sigma_px,
                   const Eigen::Vector3d& anchor_world)
    : camera_(camera),
      start_(start_px),
      end_(end_px),
      angle_weight_(angle_weight),
      inv_sigma_(InverseSigma(sigma_px)),
      anchor_(anchor_world) {}

bool LineCost::Evaluate(double const* const* parameters, double* residuals,
                        double** jacobians) const {
  Rigid3d cam_from_world;
  ParametersToPose(parameters[0], &cam_from_world);
  const OrthonormalLine line = ParametersToLine(parameters[1]);
  PluckerLine world = line.ToPlucker();
  world.n += anchor_.cross(world.v);
  Eigen::Vector3d e;
  Eigen::Matrix<double, 3, 6> d_pose;
  Eigen::Matrix<double, 3, 6> d_plucker;
  const bool want = jacobians != nullptr;
  if (!LineResidual(camera_, cam_from_world, world, start_, end_, angle_weight_, &e,
                    want ? &d_pose : nullptr, want ? &d_plucker : nullptr)) {
    return false;
  }
  // d n_world / d v = [anchor]x
  if (want && !anchor_.isZero()) {
    d_plucker.rightCols<3>() += d_plucker.leftCols<3>() * Skew(anchor_);
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

LinePriorCost::LinePriorCost(const double* reference, double weight) : weight_(weight) {
  std::copy(reference, reference + kLineSize, reference_.begin());
}

bool LinePriorCost::Evaluate(double const* const* parameters, double* residuals,
                             double** jacobians) const {
  const LineManifold manifold;
  manifold.Minus(parameters[0], reference_.data(), residuals);
  for (int i = 0; i < kLineTangentSize; ++i) residuals[i] *= weight_;
  if (jacobians && jacobians[0]) {
    // d Minus(x, ref) / d delta at x = the identity for the small steps a solve takes (exact at
    // x = ref: the residual only has to hold the line, not model the manifold's curvature);
    // lifted to the ambient block as the manifold's PlusJacobian expects.
    Eigen::Matrix<double, kLineTangentSize, kLineTangentSize> j =
        weight_ * Eigen::Matrix<double, kLineTangentSize, kLineTangentSize>::Identity();
    WriteLifted<kLineTangentSize, kLineTangentSize, kLineSize>(j, 1.0, jacobians[0]);
  }
  return true;
}

}  // namespace slslam
