#pragma once
// The rank treatment of an identification, before the fit: what the data cannot determine (coefficients that others
// or nothing explain exactly, weakly determined ones) is fixed at zero, named with the reason, and where the solver
// starts is the linearised least-squares solution of the rest. Identify (stage/identification.h) calls it.

#include <Eigen/Core>
#include <vector>

#include "stage/identification.h"
#include "stage/observation_model.h"
#include "stage/parameter_layout.h"

namespace fvm::stage {

// The coefficient in free slot `slot` of the layout.
const ParameterLayout::Coefficient& FreeCoefficient(const ParameterLayout& layout, int slot);

// The linearised least-squares solution of the kept columns (where Levenberg-Marquardt starts) and their normal
// equations.
struct KeptStart {
  std::vector<double> parameters;  // in units of the plausible sizes: the kept coefficients, then the pose
  Eigen::MatrixXd normal;          // J^T J of the kept parameters in those units, at zero error
};

// The rank treatment: what these data cannot determine is fixed at zero (result->fixed, and what the kept
// coefficients absorb of it); returns where the solver starts.
KeptStart TreatRank(const ParameterLayout& layout, const std::vector<Observation>& observations, const Prepared& prepared,
                    const IdentificationOptions& options, int equations, int pose_count, IdentificationResult& result);

}  // namespace fvm::stage
