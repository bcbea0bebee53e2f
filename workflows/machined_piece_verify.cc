#include "workflows/machined_piece_verify.h"

#include <fmt/core.h>

#include <map>

#include "core/csv.h"
#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::workflows {
namespace {

// Series of each point id from NOMINAL.csv (id,x,y,z,series).
std::map<std::string, std::string> ReadSeries(const std::string& path) {
  const CsvTable table = ReadCsv(path, CsvOptions{0, "id,x,y,z,series"});
  const int id = table.Require("id"), series = table.Require("series");
  std::map<std::string, std::string> out;
  for (const CsvRow& row : table.rows()) out[std::string(TrimBlanks(table.Text(row, id)))] = std::string(TrimBlanks(table.Text(row, series)));
  return out;
}

}  // namespace

MachineProblemOptions CmmMachineOptions() {
  MachineProblemOptions o;
  o.basis = "chebyshev";
  o.tools = {Eigen::Vector3d(0, 0, 100)};
  o.tracker = "none";
  o.unweighted = true;
  return o;
}

void MachinedPieceVerifyOptions::Check() const {
  machine.Check();
  if (order < 1 || order > 3) throw InputError(fmt::format("--order {}: use 1, 2 or 3", order));
}

bool IsSeries(const std::string& s) { return s.size() == 2 && (s[0] == 'X' || s[0] == 'Y' || s[0] == 'Z') && s[1] >= '1' && s[1] <= '3'; }

MachinedPieceVerifyResult VerifyMachinedPiece(const MachineProblem& problem, const MachinedPieceVerifyOptions& options) {
  const stage::ParameterLayout layout = problem.Layout(options.order);
  MachinedPieceVerifyResult out{
      RefusalsNamingTheData(problem, [&] { return stage::VerifyMachinedPiece(layout, problem.observations, problem.options); }),
      std::nullopt, {}, "all points", std::nullopt};
  const stage::MachinedPieceVerification& v = out.verification;
  const stage::IdentificationResult& r = v.result.identified;
  if (problem.validation) out.validation = JudgeOn(v.result, problem.validation_observations, problem.options.tool_offsets);

  // Geometric verification: which terms the series X1..Z3 alone recover (the rank of the Jacobian on them), when
  // NOMINAL.csv says which points they are; otherwise what all the points recover.
  out.geometric = v.terms;
  if (options.nominal.empty()) return out;
  const std::map<std::string, std::string> series = ReadSeries(options.nominal);
  std::vector<stage::Observation> on_series;
  for (size_t i = 0; i < problem.readings.points.size(); ++i) {
    const auto it = series.find(problem.readings.points[i].id);
    if (it != series.end() && IsSeries(it->second)) on_series.push_back(problem.observations[i]);
  }
  if (on_series.empty()) {
    throw InputError(fmt::format("{}: no point of {} belongs to a series X1..Z3; give the NOMINAL.csv of the same piece",
                                 options.nominal, problem.readings.source));
  }
  try {
    out.geometric = stage::VerifyMachinedPiece(layout, on_series, problem.options).terms;
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: the series alone: {}", options.nominal, e.what()));
  }
  out.geometric_from = fmt::format("series X1..Z3 ({} points)", on_series.size());
  // The extraction formulas on the series, in the machine frame of the datum found (the CMM readings turned back
  // by it): each error along its axis, zero-referenced at the axis' origin.
  const Eigen::Matrix3d turn = r.pose.Rotation();
  std::map<std::string, std::vector<stage::SeriesPoint>> by_series;
  for (size_t i = 0; i < problem.readings.points.size(); ++i) {
    const artefacts::TrackerReading& p = problem.readings.points[i];
    const auto it = series.find(p.id);
    if (it == series.end() || !IsSeries(it->second) || p.tool != 0) continue;
    by_series[it->second].push_back({p.nominal, turn * p.measured + r.pose.translation - (p.nominal + problem.chain.tool_offset)});
  }
  out.extraction = stage::ExtractGeometricErrors(by_series, problem.chain.tool_offset.z(), problem.workspace.min);
  return out;
}

}  // namespace fvm::workflows
