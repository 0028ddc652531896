#include "slslam/optimization/manifolds.h"

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"

namespace slslam {

namespace {

using RowMajorMap =
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

// [B; 0] (ambient x B's columns, row-major) and its transpose [B^T, 0] (B's columns x ambient):
// B spans directions of the tangent, whose coordinates are the first B.rows() ambient columns of
// the costs' Jacobians.
// (templates, so the identity below stays an expression: no allocation in Ceres' Jacobian path)
template <class Basis>
void Lifted(const Eigen::MatrixBase<Basis>& basis, int ambient, double* jacobian) {
  RowMajorMap j(jacobian, ambient, basis.cols());
  j.setZero();
  j.topRows(basis.rows()) = basis;
}

template <class Basis>
void Lowered(const Eigen::MatrixBase<Basis>& basis, int ambient, double* jacobian) {
  RowMajorMap j(jacobian, basis.cols(), ambient);
  j.setZero();
  j.leftCols(basis.rows()) = basis.transpose();
}

// [I; 0] (ambient x tangent) and its transpose [I, 0] (tangent x ambient).
void LiftedIdentity(int ambient, int tangent, double* jacobian) {
  Lifted(Eigen::MatrixXd::Identity(tangent, tangent), ambient, jacobian);
}

void LoweredIdentity(int ambient, int tangent, double* jacobian) {
  Lowered(Eigen::MatrixXd::Identity(tangent, tangent), ambient, jacobian);
}

}  // namespace

void PoseToParameters(const Rigid3d& cam_from_world, double* params) {
  Eigen::Map<Eigen::Vector3d> t(params);
  t = cam_from_world.translation;
  Eigen::Map<Eigen::Quaterniond>(params + 3) =
      Eigen::Quaterniond(cam_from_world.rotation).normalized();
}

void ParametersToPose(const double* params, Rigid3d* cam_from_world) {
  cam_from_world->translation = Eigen::Map<const Eigen::Vector3d>(params);
  cam_from_world->rotation =
      Eigen::Map<const Eigen::Quaterniond>(params + 3).normalized().toRotationMatrix();
}

void LineToParameters(const OrthonormalLine& line, double* params) {
  Eigen::Map<Eigen::Quaterniond> q(params);
  q = line.U.normalized();
  params[4] = line.phi;
}

OrthonormalLine ParametersToLine(const double* params) {
  OrthonormalLine line;
  line.U = Eigen::Map<const Eigen::Quaterniond>(params).normalized();
  line.phi = params[4];
  return line;
}

bool PoseManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Map<const Eigen::Vector3d> t(x);
  const Eigen::Map<const Eigen::Quaterniond> q(x + 3);
  const Eigen::Map<const Eigen::Vector3d> rho(delta);
  const Eigen::Quaterniond dq = ExpQuaternion(Eigen::Map<const Eigen::Vector3d>(delta + 3));
  Eigen::Map<Eigen::Vector3d> t_out(x_plus_delta);
  t_out = dq * t + rho;
  Eigen::Map<Eigen::Quaterniond>(x_plus_delta + 3) = (dq * q).normalized();
  return true;
}

bool PoseManifold::PlusJacobian(const double*, double* jacobian) const {
  LiftedIdentity(kPoseSize, kPoseTangentSize, jacobian);
  return true;
}

bool PoseManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  // delta with Plus(x, delta) = y: omega = Log(q_y q_x^-1), rho = t_y - Exp(omega) t_x.
  const Eigen::Map<const Eigen::Quaterniond> qx(x + 3);
  const Eigen::Map<const Eigen::Quaterniond> qy(y + 3);
  const Eigen::Quaterniond dq = (qy * qx.conjugate()).normalized();
  Eigen::Map<Eigen::Vector3d>(y_minus_x + 3) = LogSO3(dq);
  Eigen::Map<Eigen::Vector3d> rho(y_minus_x);
  rho = Eigen::Map<const Eigen::Vector3d>(y) - dq * Eigen::Map<const Eigen::Vector3d>(x);
  return true;
}

bool PoseManifold::MinusJacobian(const double*, double* jacobian) const {
  LoweredIdentity(kPoseSize, kPoseTangentSize, jacobian);
  return true;
}

bool LineManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  Eigen::Vector4d d(delta[0], delta[1], delta[2], delta[3]);
  LineToParameters(ParametersToLine(x).Plus(d), x_plus_delta);
  return true;
}

bool LineManifold::PlusJacobian(const double*, double* jacobian) const {
  LiftedIdentity(kLineSize, kLineTangentSize, jacobian);
  return true;
}

bool LineManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  const OrthonormalLine lx = ParametersToLine(x);
  const OrthonormalLine ly = ParametersToLine(y);
  Eigen::Map<Eigen::Vector3d> theta(y_minus_x);
  theta = LogSO3(lx.U.conjugate() * ly.U);
  y_minus_x[3] = ly.phi - lx.phi;
  return true;
}

bool LineManifold::MinusJacobian(const double*, double* jacobian) const {
  LoweredIdentity(kLineSize, kLineTangentSize, jacobian);
  return true;
}

LineSubspaceManifold::LineSubspaceManifold(const Basis& basis) : basis_(basis) {
  Require(basis_.cols() >= 1 && basis_.cols() <= kLineTangentSize,
          "a line subspace needs 1 to 4 directions");
}

bool LineSubspaceManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Vector4d d = basis_ * Eigen::Map<const Eigen::VectorXd>(delta, basis_.cols());
  LineToParameters(ParametersToLine(x).Plus(d), x_plus_delta);
  return true;
}

bool LineSubspaceManifold::PlusJacobian(const double*, double* jacobian) const {
  Lifted(basis_, kLineSize, jacobian);
  return true;
}

bool LineSubspaceManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  Eigen::Vector4d d;
  LineManifold().Minus(y, x, d.data());
  Eigen::Map<Eigen::VectorXd>(y_minus_x, basis_.cols()) = basis_.transpose() * d;
  return true;
}

bool LineSubspaceManifold::MinusJacobian(const double*, double* jacobian) const {
  Lowered(basis_, kLineSize, jacobian);
  return true;
}

}  // namespace slslam
