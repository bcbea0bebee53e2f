#pragma once
// The inverse of the forward model: which command q puts the tool on a nominal target p (Newton iteration).

#include <Eigen/Core>

#include "stage/parameter_layout.h"

namespace fvm::stage {

struct InverseOptions {
  double tolerance_mm = 1e-12;  // stop when the Newton step is below this (quadratic convergence: the error left is far smaller)
  int max_iterations = 20;
};

struct InverseResult {
  Eigen::Vector3d command = Eigen::Vector3d::Zero();
  int iterations = 0;
  bool converged = false;
};

// Solves Forward(layout, free, q) = target for q, starting from the error-free command.
InverseResult Inverse(const ParameterLayout& layout, const double* free, const Eigen::Vector3d& target,
                      const InverseOptions& options = {});

}  // namespace fvm::stage
