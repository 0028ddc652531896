// Checks a Ceres cost's Jacobians the way Ceres sees them (J_ambient * PlusJacobian) against
// central differences of residual(Plus(x, delta)), for the optimization gtests.
#pragma once

#include <algorithm>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/manifold.h>
#include <gtest/gtest.h>
#include <Eigen/Core>

namespace slslam::test {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Checks every parameter block's tangent Jacobian of `cost`; manifolds[i] may be null (Euclidean).
inline void CheckCost(const ceres::CostFunction& cost, std::vector<std::vector<double>> params,
                      const std::vector<const ceres::Manifold*>& manifolds) {
  const int rows = cost.num_residuals();
  const auto& sizes = cost.parameter_block_sizes();
  std::vector<const double*> ptrs;
  for (auto& p : params) ptrs.push_back(p.data());
  std::vector<RowMatrix> ambient;
  std::vector<double*> jac_ptrs;
  for (int size : sizes) ambient.emplace_back(rows, size);
  for (auto& j : ambient) jac_ptrs.push_back(j.data());
  Eigen::VectorXd residual(rows);
  ASSERT_TRUE(cost.Evaluate(ptrs.data(), residual.data(), jac_ptrs.data()));

  for (size_t b = 0; b < params.size(); ++b) {
    const ceres::Manifold* m = manifolds[b];
    const int tangent = m ? m->TangentSize() : sizes[b];
    RowMatrix lift = RowMatrix::Identity(sizes[b], tangent);
    if (m) m->PlusJacobian(params[b].data(), lift.data());
    const Eigen::MatrixXd analytic = ambient[b] * lift;
    Eigen::MatrixXd numeric(rows, tangent);
    const double h = 1e-6;
    for (int k = 0; k < tangent; ++k) {
      Eigen::VectorXd r_plus(rows), r_minus(rows);
      for (int sign : {1, -1}) {
        std::vector<double> delta(tangent, 0.0);
        delta[k] = sign * h;
        std::vector<double> moved(sizes[b]);
        if (m) {
          m->Plus(params[b].data(), delta.data(), moved.data());
        } else {
          for (int i = 0; i < sizes[b]; ++i) moved[i] = params[b][i] + delta[i];
        }
        std::vector<const double*> p2 = ptrs;
        p2[b] = moved.data();
        ASSERT_TRUE(cost.Evaluate(p2.data(), (sign > 0 ? r_plus : r_minus).data(), nullptr));
      }
      numeric.col(k) = (r_plus - r_minus) / (2 * h);
    }
    const double scale = std::max(1.0, numeric.cwiseAbs().maxCoeff());
    EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-6 * scale)
        << "block " << b << "\nanalytic\n"
        << analytic << "\nnumeric\n"
        << numeric;
  }
}

}  // namespace slslam::test
