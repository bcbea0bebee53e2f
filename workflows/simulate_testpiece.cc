#include "workflows/simulate_testpiece.h"

#include <fmt/core.h>

#include "artefacts/io/machine_truth_file.h"
#include "artefacts/simulation/machine_tool_simulation.h"
#include "artefacts/simulation/machined_piece_simulation.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "workflows/machine_summary.h"
#include "workflows/machined_piece_verify.h"

namespace fvm::workflows {
namespace {

// The series cut again with the tools that make the Z and Y yaws and the Z rotations observable: a boring bar whose
// edge sits 30 mm off the spindle axis, spindle oriented (M19) at 0 and 180 deg, and a tool 50 mm longer.
std::vector<Eigen::Vector3d> ProposedTools(const Eigen::Vector3d& tool) {
  return {tool + Eigen::Vector3d(30, 0, 0), tool - Eigen::Vector3d(30, 0, 0), tool + Eigen::Vector3d(0, 0, 50)};
}

std::vector<artefacts::PiecePoint> ChosenPoints(const artefacts::MachinedPieceDescription& piece, const std::string& only) {
  std::vector<artefacts::PiecePoint> points = artefacts::NominalPoints(piece);
  if (only != "all") {
    std::erase_if(points, [&](const artefacts::PiecePoint& p) {
      return only == "pyramid" ? p.kind != artefacts::FeatureKind::kPyramid : !IsSeries(p.series);
    });
  }
  return points;
}

// The series measured again with each proposed tool (seeds seed + 1, + 2, + 3), appended to `out`.
void CutProposedSeries(const stage::AxisChain& chain, const artefacts::MachineTruth& truth,
                       const std::vector<artefacts::PiecePoint>& points, const artefacts::CmmSimulation& cmm,
                       SimulatedTestPiece& out) {
  std::vector<artefacts::PiecePoint> series;
  for (const artefacts::PiecePoint& p : points) {
    if (IsSeries(p.series)) series.push_back(p);
  }
  const std::vector<Eigen::Vector3d> tools = ProposedTools(chain.tool_offset);
  for (size_t k = 0; k < tools.size(); ++k) {
    std::vector<artefacts::PiecePoint> again = series;
    for (artefacts::PiecePoint& p : again) p.id += fmt::format("-t{}", k + 2);
    stage::AxisChain other = chain;
    other.tool_offset = tools[k];
    artefacts::CmmSimulation c = cmm;
    c.seed = cmm.seed + k + 1;
    for (artefacts::TrackerReading r : artefacts::SimulateMachinedPiece(other, truth, again, c).points) {
      r.tool = static_cast<int>(k) + 1;
      out.measured.points.push_back(r);
    }
    out.nominal.insert(out.nominal.end(), again.begin(), again.end());
    out.tools.push_back(tools[k]);
  }
}

// What made the errors: the truth file given, "random" or the published test functions.
std::string ErrorsName(const SimulateTestPieceOptions& o) {
  return !o.errors.empty() ? o.errors : o.mean_error_um > 0 ? std::string("random") : std::string("[Lorente 2021] Table 4");
}

}  // namespace

void SimulateTestPieceOptions::Check() const {
  if (points != "all" && points != "pyramid" && points != "series") {
    throw InputError(fmt::format("--points {}: use all, pyramid or series", points));
  }
  try {
    stage::AxisChain::Parse(chain);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("--chain {}: {}", chain, e.what()));
  }
  if (!(noise_um >= 0)) throw InputError(fmt::format("--noise-um {}: give 0 or more", noise_um));
  if (!(mean_error_um >= 0)) throw InputError(fmt::format("--mean-error-um {}: give 0 (none) or more", mean_error_um));
  if (validation_step && !(validation_step->minCoeff() > 0)) throw InputError("--validation: steps must be > 0 mm");
}

SimulatedTestPiece SimulateTestPiece(const SimulateTestPieceOptions& o) {
  const artefacts::MachinedPieceDescription piece =
      o.piece.empty() ? artefacts::PublishedMachinedPiece() : artefacts::ReadMachinedPiece(o.piece);
  const std::vector<artefacts::PiecePoint> points = ChosenPoints(piece, o.points);
  stage::AxisChain chain = stage::AxisChain::Parse(o.chain);
  chain.tool_offset = o.tool;
  const artefacts::Workspace ws = artefacts::PieceWorkspace(piece);
  const artefacts::MachineTruth truth = !o.errors.empty()       ? artefacts::ReadMachineTruth(o.errors, ws)
                                        : o.mean_error_um > 0.0 ? artefacts::RandomMachineTruth(chain, ws, o.seed, o.mean_error_um)
                                                                : artefacts::PublishedTestFunctions(ws);
  artefacts::CmmSimulation cmm;
  cmm.datum = o.datum;
  cmm.sigma_mm = o.noise_um * 1e-3;
  cmm.seed = o.seed;
  SimulatedTestPiece out;
  out.measured = artefacts::SimulateMachinedPiece(chain, truth, points, cmm);
  out.nominal = points;
  out.tools = {chain.tool_offset};
  if (o.proposed_series) CutProposedSeries(chain, truth, points, cmm, out);
  out.measured.comments = {fmt::format("fvm simulate testpiece: {} points, CMM noise {} um, seed {}", points.size(), o.noise_um, o.seed)};
  if (o.validation_step) {
    // A noise-free grid over the whole piece (not only where features are): how well the identified machine
    // predicts the piece everywhere.
    std::vector<artefacts::PiecePoint> grid;
    for (const artefacts::PlannedPoint& p : artefacts::PlanMesh(ws, *o.validation_step)) grid.push_back({"G" + p.id.substr(1), p.nominal, "", "", {}});
    artefacts::CmmSimulation exact = cmm;
    exact.sigma_mm = 0.0;
    out.validation = artefacts::SimulateMachinedPiece(chain, truth, grid, exact);
    out.validation->comments = {"fvm simulate testpiece: noise-free validation grid over the piece"};
  }
  out.truth = nlohmann::json::parse(artefacts::MachineTruthJson(truth));
  out.truth["chain"] = chain.code;
  out.truth["tool_mm"] = {chain.tool_offset.x(), chain.tool_offset.y(), chain.tool_offset.z()};
  out.truth["datum"] = PoseJson(cmm.datum, nullptr);
  out.truth["cmm_noise_um"] = o.noise_um;
  out.truth["seed"] = o.seed;
  out.truth["errors"] = ErrorsName(o);
  return out;
}

void WriteFiles(const SimulatedTestPiece& simulated, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  artefacts::WriteNominalPoints((dir / "nominal.csv").string(), simulated.nominal);
  artefacts::WriteTrackerReadings(dir / "measured.csv", simulated.measured);
  if (simulated.validation) artefacts::WriteTrackerReadings(dir / "validation.csv", *simulated.validation);
  WriteFileAtomically(dir / "truth.json", simulated.truth.dump(2) + "\n");
}

Summary Summarize(const SimulatedTestPiece& simulated, const SimulateTestPieceOptions& o, const std::string& output) {
  Summary s;
  s.json = nlohmann::json{{"points", simulated.measured.points.size()}, {"errors", ErrorsName(o)},
            {"cmm_noise_um", o.noise_um}, {"seed", o.seed}, {"datum", PoseJson(o.datum, nullptr)}};
  s.text = fmt::format("simulated the test piece into {}: {} points ({}), errors {}, CMM noise {} um, seed {}\n", output,
                       simulated.measured.points.size(), o.points, ErrorsName(o), o.noise_um, o.seed);
  if (o.proposed_series) {
    const Eigen::Vector3d& tool = simulated.tools.front();
    std::string tools = fmt::format("--tool {},{},{}", tool.x(), tool.y(), tool.z());
    for (size_t k = 1; k < simulated.tools.size(); ++k) {
      const Eigen::Vector3d& t = simulated.tools[k];
      tools += fmt::format(" --tool {},{},{}", t.x(), t.y(), t.z());
    }
    s.text += fmt::format("  the series cut again with three more tools (the `tool` column): verify with {}\n", tools);
  }
  return s;
}

}  // namespace fvm::workflows
