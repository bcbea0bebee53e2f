#pragma once
// fvm testpiece verify as a job: a machine verified from the CMM measurement of the test piece it cut [Lorente 2021].
// The kinematics are fvm verify's (workflows/machine_problem.h): a CMM-measured piece is a tracker whose pose is the
// piece's datum. Adds the iteration log, which errors the points (or the series X1..Z3 alone) recover, and the
// series' extraction formulas.

#include <optional>
#include <string>
#include <vector>

#include "stage/series_extraction.h"
#include "stage/machined_piece_verification.h"
#include "workflows/machine_problem.h"

namespace fvm::workflows {

// fvm verify's machine options as a CMM-measured piece takes them: Chebyshev polynomials, a 100 mm tool, equal
// weights (a CMM has no tracker noise model).
MachineProblemOptions CmmMachineOptions();

struct MachinedPieceVerifyOptions {
  MachineProblemOptions machine = CmmMachineOptions();  // DATA (id,x,y,z,xm,ym,zm), --chain, --basis, --tool, ...
  int order = 2;        // polynomial order of each error function
  std::string nominal;  // NOMINAL.csv id,x,y,z,series of the piece: its series X1..Z3; empty: all points judge
  void Check() const;   // the machine's options, and --order 1-3
};

struct MachinedPieceVerifyResult {
  stage::MachinedPieceVerification verification;
  std::optional<VolumetricChange> validation;  // the held-out readings, when the problem has them
  std::vector<stage::TermRecovery> geometric;  // per error: recovered by the series alone (or all points)
  std::string geometric_from;                  // "all points" or "series X1..Z3 (N points)"
  // With a nominal file: each error along its axis from the series' extraction formulas, in the machine frame of
  // the datum found, zero-referenced at the axis' origin (mm or rad).
  std::optional<std::vector<stage::ExtractedError>> extraction;
};

// Refusals name the data or nominal file: a verification the data refuse, a nominal file with no point of a series,
// series that alone cannot be verified.
MachinedPieceVerifyResult VerifyMachinedPiece(const MachineProblem& problem, const MachinedPieceVerifyOptions& options);

// "X1".."Z3": the series of the geometric verification.
bool IsSeries(const std::string& name);

}  // namespace fvm::workflows
