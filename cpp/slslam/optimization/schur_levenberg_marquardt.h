// Levenberg-Marquardt for bundle adjustment with the landmarks eliminated: the library's own
// solver of local BA's passes (BundleAdjustmentOptions::own_solver), on the same cost functions
// and with Ceres' trust-region rules, without a Ceres problem.
//
// Every landmark (point: 3 parameters; line: the 4-dim tangent of its orthonormal representation)
// touches the poses only, so each one's block is eliminated on its own (a Schur complement of
// fixed-size blocks), and what remains is a dense system over the free poses' 6-dim tangents: a
// local BA window has at most a few tens of free keyframes.
#pragma once

#include <atomic>
#include <vector>

#include <ceres/cost_function.h>

namespace slslam {

// One residual block: a cost of (pose, landmark) whose Jacobians hold the tangent Jacobian in their
// leading columns (cost_functions.h: pose 7 ambient / 6 tangent, point 3 / 3, line 5 / 4), and
// its loss: weight * Huber(huber) in the robust pass (huber > 0), weight * squared norm otherwise.
struct SchurTerm {
  const ceres::CostFunction* cost = nullptr;  ///< not owned; 2 or 3 residuals
  int pose = 0;                               ///< index into SchurBlocks::poses
  int landmark = 0;                           ///< index into SchurBlocks::points or ::lines
  bool line = false;
  double huber = 0.0;   ///< Huber threshold on the whitened residual's norm [-]; 0: none
  double weight = 1.0;  ///< scale of the term's cost [-]
};

// The parameter blocks, in place: ambient values that the solve reads and, when it ends with a
// usable estimate, overwrites. Blocks no term touches are left alone.
struct SchurBlocks {
  std::vector<double*> poses;    ///< 7 values each (PoseManifold)
  std::vector<bool> pose_fixed;  ///< per pose: held
  std::vector<double*> points;   ///< 3 values each
  std::vector<double*> lines;    ///< 5 values each (LineManifold)
};

struct SchurSolveSummary {
  int steps = 0;             ///< trust-region steps tried (Ceres' iterations after the start) [-]
  int rejected_steps = 0;    ///< of which the cost rose or could not be evaluated [-]
  bool moved = false;        ///< a step was accepted
  bool usable = false;       ///< the start could be evaluated: the blocks hold a usable estimate
  bool aborted = false;      ///< `abort` ended it; the blocks are as given
  bool interrupted = false;  ///< `interrupt` ended it at the last accepted iterate
  double initial_cost = 0.0;
  double final_cost = 0.0;
};

// Minimises 1/2 sum weight * rho(|r|^2) over the free poses and every touched landmark, with
// Ceres' Levenberg-Marquardt rules (as SolvePoseLevenbergMarquardt in pose_optimizer.cpp): first
// radius 1e4 (at most 1e16, the solve ends below 1e-32), Jacobi scaling computed at the start,
// damping by the scaled diagonal clamped to [1e-6, 1e32], a step of quality above 1e-3 accepted,
// the radius grown by 1 / max(1/3, 1 - (2 quality - 1)^3) or cut by a doubling factor; it stops
// at a gradient of 1e-10, a step of 1e-8 relative to the parameters, after an accepted step that
// lowered the cost by at most 1e-6 of it, or after `max_iterations` steps, rejected ones included.
// `abort` and `interrupt` are polled before each step, as Ceres' callbacks.
SchurSolveSummary SolveSchurLevenbergMarquardt(const std::vector<SchurTerm>& terms,
                                               const SchurBlocks& blocks, int max_iterations,
                                               const std::atomic<bool>* abort = nullptr,
                                               const std::atomic<bool>* interrupt = nullptr);

}  // namespace slslam
