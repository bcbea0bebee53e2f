#include "artefacts/simulation/machined_piece_simulation.h"

#include "core/random.h"
#include "stage/error_terms.h"
#include "stage/tracker.h"

namespace fvm::artefacts {

MachineTruth PublishedTestFunctions(const Workspace& ws) {
  MachineTruth truth;
  truth.workspace = ws;
  // {ISO name, linear, quadratic} as [Lorente 2021] Table 4 prints them (mm or rad per mm^i).
  struct Published {
    const char* iso;
    double c1, c2;
  };
  const Published table[] = {
      {"EXX", -1.5e-4, 4.5e-8},  {"EYX", 0, -3.35e-8},      {"EZX", 0, 5e-8},
      {"EAX", -1.1e-6, -2.2e-10}, {"EBX", 2.1e-6, -7.2e-10}, {"ECX", -1.7e-6, 1.4e-10},
      {"EXY", -6.4e-5, 5.1e-8},  {"EYY", 6.07e-5, -3.56e-8}, {"EZY", 0, -1.19e-7},
      {"EAY", 4.6e-6, -3.2e-10}, {"EBY", -3.2e-6, 5.7e-10},  {"ECY", 2.6e-6, 4.6e-10},
      {"EXZ", 1.2e-5, 1.8e-7},   {"EYZ", -4.2e-5, -4.96e-8}, {"EZZ", 1.36e-4, -6.03e-8},
      {"EAZ", -2.2e-6, -3.3e-10}, {"EBZ", -5.5e-6, 8.2e-10}, {"ECZ", 6.1e-6, 6.2e-10},
  };
  for (const Published& p : table) {
    TermTruth& t = truth.terms[static_cast<size_t>(*stage::FindErrorTerm(p.iso))];
    t.poly = {0.0, p.c1, p.c2, 0.0};
  }
  truth.terms[static_cast<size_t>(stage::SquarenessTerm(stage::Axis::kX, stage::Axis::kY))].poly[0] = 4e-4;
  truth.terms[static_cast<size_t>(stage::SquarenessTerm(stage::Axis::kX, stage::Axis::kZ))].poly[0] = -5e-4;
  truth.terms[static_cast<size_t>(stage::SquarenessTerm(stage::Axis::kY, stage::Axis::kZ))].poly[0] = -9.5e-4;
  return truth;
}

Workspace PieceWorkspace(const MachinedPieceDescription& piece) {
  Workspace ws;
  ws.min = piece.origin;
  ws.max = piece.origin + piece.envelope;
  return ws;
}

TrackerReadings SimulateMachinedPiece(const stage::AxisChain& chain, const MachineTruth& truth, const std::vector<PiecePoint>& points,
                                  const CmmSimulation& cmm, TrackerReadings* noise_free) {
  // The cut is the tracker model with the CMM as the instrument at the datum and no tracker noise ...
  stage::AxisChain cut = chain;
  cut.instrument = cmm.datum;
  std::vector<PlannedPoint> planned;
  for (const PiecePoint& p : points) planned.push_back({p.id, p.machine, ""});
  TrackerReadings exact = SimulateTrackerReadings(cut, truth, planned, stage::TrackerNoise::Preset("none"), cmm.seed);
  exact.cmm = true;
  // ... and the CMM's isotropic probing noise, from its own stream of the seed.
  Random random(StreamSeed(cmm.seed, 1));
  TrackerReadings noisy = exact;
  for (TrackerReading& r : noisy.points) {
    for (int k = 0; k < 3; ++k) r.measured[k] += cmm.sigma_mm * random.Normal();
  }
  if (noise_free != nullptr) *noise_free = std::move(exact);
  return noisy;
}

}  // namespace fvm::artefacts
