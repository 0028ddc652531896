// Shared fixtures of the C++ tests: the EuRoC-like stereo rig most tests project with, and
// central-difference Jacobians for checking analytic ones.
#pragma once

#include <algorithm>
#include <functional>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "slslam/core/stereo_rig.h"

namespace slslam::test {

// 752 x 480, fx 458, fy 457, principal point (367, 248), baseline 0.11 m (EuRoC's cam0 / cam1
// after rectification, rounded).
inline StereoRig EurocLikeRig() {
  StereoRig rig;
  rig.camera.fx = 458.0;
  rig.camera.fy = 457.0;
  rig.camera.cx = 367.0;
  rig.camera.cy = 248.0;
  rig.camera.width = 752;
  rig.camera.height = 480;
  rig.baseline_m = 0.11;
  return rig;
}

// Central differences (step 1e-6) of f over a `cols`-dimensional increment around 0.
template <int Rows>
Eigen::Matrix<double, Rows, Eigen::Dynamic> NumericJacobian(
    int cols, const std::function<Eigen::Matrix<double, Rows, 1>(const Eigen::VectorXd&)>& f) {
  const double h = 1e-6;
  Eigen::Matrix<double, Rows, Eigen::Dynamic> j(Rows, cols);
  for (int k = 0; k < cols; ++k) {
    Eigen::VectorXd d = Eigen::VectorXd::Zero(cols);
    d(k) = h;
    j.col(k) = (f(d) - f(-d)) / (2 * h);
  }
  return j;
}

// Relative comparison of an analytic Jacobian with a numeric one: residual Jacobians are in
// pixels per unit and reach 1e3, so the bound scales with the largest entry.
template <typename A, typename B>
void ExpectClose(const A& analytic, const B& numeric, double rel = 1e-6) {
  const double scale = std::max(1.0, numeric.cwiseAbs().maxCoeff());
  EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), rel * scale) << "analytic\n"
                                                                     << analytic << "\nnumeric\n"
                                                                     << numeric;
}

}  // namespace slslam::test
