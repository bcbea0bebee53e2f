#pragma once
// A simulated machine tool for the machine-tool jobs' tests: an XFYZ machine of 1000 x 800 x 600 mm whose errors
// are cubics of 100 um mean volumetric error (no sine: an order-3 model can take them exactly, so what is left is the
// tracker's noise alone), read by an absolute distance meter ([Aguado 2016] Table 3, tracker C: about 10 um at 2 m)
// from [IJSIMM 2016] Table I's position 4, and the same readings without noise (the truth).

#include <cmath>
#include <filesystem>
#include <string>

#include "artefacts/io/tracker_readings.h"
#include "artefacts/simulation/machine_tool_simulation.h"
#include "stage/tracker.h"

namespace fvm::workflows::testing {

struct SimulatedMachine {
  stage::AxisChain chain;  // tool (0, 0, 100) mm, the tracker as its instrument
  artefacts::MachineTruth truth;
  artefacts::TrackerReadings readings, noise_free;
};

inline artefacts::Workspace TestWorkspace() {
  artefacts::Workspace ws;
  ws.max = Eigen::Vector3d(1000, 800, 600);
  return ws;
}

// `seed` draws the machine and the noise; `step` (mm) spaces the mesh of commanded points; `mean_error_um` sizes
// the errors (over the workspace, sines included before they are taken out); `positioning_cubic_um` adds a cubic
// of that size at the end of each axis to its positioning error, which only order 3 takes.
inline SimulatedMachine SimulateMachine(std::uint64_t seed, double step = 250.0, double mean_error_um = 100.0,
                                        double positioning_cubic_um = 0.0) {
  SimulatedMachine m;
  m.chain = stage::AxisChain::Parse("XFYZ");
  m.chain.tool_offset = Eigen::Vector3d(0, 0, 100);
  m.chain.instrument = stage::Pose::FromEulerXyzDegrees(Eigen::Vector3d(1100, -1000, 600), Eigen::Vector3d(63, 14, 35));
  m.truth = artefacts::RandomMachineTruth(m.chain, TestWorkspace(), seed, mean_error_um);
  for (artefacts::TermTruth& t : m.truth.terms) t.sine_amplitude = 0.0, t.sine_pitch_mm = 0.0;
  const artefacts::Workspace ws = TestWorkspace();
  for (int k = 0; k < 3; ++k) {  // xTx, yTy, zTz: terms 0, 7, 14 (axis * 6 + direction: stage/error_terms.h)
    m.truth.terms[static_cast<size_t>(7 * k)].poly[3] += positioning_cubic_um * 1e-3 / std::pow(ws.max[k] - ws.min[k], 3);
  }
  const auto points = artefacts::PlanMesh(TestWorkspace(), Eigen::Vector3d::Constant(step));
  m.readings = artefacts::SimulateTrackerReadings(m.chain, m.truth, points, stage::TrackerNoise::Preset("adm"),
                                                  seed, &m.noise_free);
  m.readings.source = m.noise_free.source = "simulated";
  return m;
}

}  // namespace fvm::workflows::testing
