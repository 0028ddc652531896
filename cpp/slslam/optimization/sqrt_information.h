// The square root of an information matrix, for whitening residuals in Ceres costs.
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

namespace slslam {

// L with L^T L = info for a symmetric positive semi-definite information matrix (symmetrised
// first; negative eigenvalues of a rounded matrix clamped to 0).
template <int N>
Eigen::Matrix<double, N, N> SqrtInformation(const Eigen::Matrix<double, N, N>& info) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eig(0.5 * (info + info.transpose()));
  const Eigen::Matrix<double, N, 1> d = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return d.asDiagonal() * eig.eigenvectors().transpose();
}

}  // namespace slslam
