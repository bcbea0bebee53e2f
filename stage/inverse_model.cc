#include "stage/inverse_model.h"

#include <ceres/jet.h>

#include <Eigen/LU>
#include <vector>

#include "core/dense_decomposition.h"

namespace fvm::stage {

InverseResult Inverse(const ParameterLayout& layout, const double* free, const Eigen::Vector3d& target,
                      const InverseOptions& options) {
  using Jet = ceres::Jet<double, 3>;
  const AxisChain& chain = layout.chain();
  std::vector<Jet> free_jets(static_cast<size_t>(layout.NumFree()));
  for (int i = 0; i < layout.NumFree(); ++i) free_jets[static_cast<size_t>(i)] = Jet(free[i]);

  // Without errors the forward model is the identity followed by the instrument frame, so the error-free
  // command is the target taken back out of the instrument frame.
  InverseResult result;
  result.command = chain.instrument ? Eigen::Vector3d(chain.instrument->Rotation() * target + chain.instrument->translation)
                                    : target;
  for (result.iterations = 1; result.iterations <= options.max_iterations; ++result.iterations) {
    Eigen::Matrix<Jet, 3, 1> q;
    for (int k = 0; k < 3; ++k) q[k] = Jet(result.command[k], k);
    const Eigen::Matrix<Jet, 3, 1> p = Forward(layout, free_jets.data(), q);
    Eigen::Matrix3d jacobian;
    Eigen::Vector3d residual;
    for (int r = 0; r < 3; ++r) {
      jacobian.row(r) = p[r].v.transpose();
      residual[r] = p[r].a - target[r];
    }
    const Eigen::Vector3d step =
        Decompose<Eigen::PartialPivLU<Eigen::Matrix3d>>(jacobian, "the inverse model's Newton step").solve(residual);
    result.command -= step;
    if (step.norm() < options.tolerance_mm) {
      result.converged = true;
      break;
    }
  }
  return result;
}

}  // namespace fvm::stage
