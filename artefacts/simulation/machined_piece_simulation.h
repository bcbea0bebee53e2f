#pragma once
// A test piece cut by a machine with known geometric errors and measured on a CMM ([Lorente 2021]), with the truth
// recorded: what `fvm simulate testpiece` writes and the test piece's tests judge `fvm testpiece verify` against.
//
// The tool commanded to q cuts the feature point at the part coordinates F(e(q), q) of the machine's kinematic
// chain (stage/axis_chain.h, tool offset included); the CMM reads that point in its own frame, where the piece
// lies at its datum: xm = R^-1 (F - t) for the datum pose (t, R) -- exactly a tracker on the table, so the
// readings share the tracker's type and the verification its solver. CMM noise is normal, isotropic, `sigma` per
// coordinate (a CMM's probing error is nearly isotropic, unlike a tracker's).

#include <cstdint>
#include <vector>

#include "artefacts/geometry/machined_piece.h"
#include "artefacts/io/tracker_readings.h"
#include "artefacts/simulation/machine_tool_simulation.h"
#include "stage/axis_chain.h"
#include "stage/pose.h"

namespace fvm::artefacts {

// The test functions of [Lorente 2021] Table 4 on the machine's travel from ws.min: per term
//   EXX 4.5e-8 x^2 - 1.5e-4 x, EYX -3.35e-8 x^2, ... (mm, rad; x in mm from the axis' origin),
// the squareness terms as the constant angles of their published effects (ECO 4e-4 x: xWy = 4e-4 rad;
// EBO -5e-4 x: xWz; EAO -9.5e-4 y: yWz).
MachineTruth PublishedTestFunctions(const Workspace& ws);

// The workspace a piece spans: its envelope in machine coordinates.
Workspace PieceWorkspace(const MachinedPieceDescription& piece);

struct CmmSimulation {
  stage::Pose datum;            // the piece in the CMM frame: machine (part) coordinates -> CMM by ToPosedFrame
  double sigma_mm = 0.001;      // CMM noise per coordinate
  std::uint64_t seed = 1;
};

// The CMM readings (cmm = true: id,x,y,z,xm,ym,zm) of the piece cut by `truth` on `chain` at `points`; the
// noise-free readings go to `noise_free` when given.
TrackerReadings SimulateMachinedPiece(const stage::AxisChain& chain, const MachineTruth& truth, const std::vector<PiecePoint>& points,
                                  const CmmSimulation& cmm, TrackerReadings* noise_free = nullptr);

}  // namespace fvm::artefacts
