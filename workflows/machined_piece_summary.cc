#include "workflows/machined_piece_summary.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/histogram.h"
#include "workflows/machine_summary.h"

namespace fvm::workflows {
namespace {

constexpr const char* kCmmWeights = "equal (CMM)";

nlohmann::json TermsJson(const std::vector<stage::TermRecovery>& terms) {
  nlohmann::json out = nlohmann::json::array();
  for (const stage::TermRecovery& t : terms) {
    nlohmann::json j{{"error", t.error}, {"vdi", t.vdi}, {"recoverable", t.recoverable}, {"value_um_or_urad", t.value}, {"u", t.u}};
    if (t.partly) j["partly"] = true;
    if (!t.reason.empty()) j["reason"] = t.reason;
    out.push_back(j);
  }
  return out;
}

nlohmann::json ExtractionJson(const std::vector<stage::ExtractedError>& extraction) {
  nlohmann::json out = nlohmann::json::array();
  for (const stage::ExtractedError& e : extraction) {
    const bool angle = e.error[1] == 'A' || e.error[1] == 'B' || e.error[1] == 'C';
    nlohmann::json values = nlohmann::json::array();
    for (double x : e.value) values.push_back(x * (angle ? 1e6 : 1e3));
    out.push_back({{"error", e.error}, {"coordinate_mm", e.coordinate}, {"value_um_or_urad", values}});
  }
  return out;
}

nlohmann::json VerifyJson(const MachineProblem& problem, const MachinedPieceVerifyOptions& options,
                          const MachinedPieceVerifyResult& verified) {
  const stage::MachinedPieceVerification& v = verified.verification;
  nlohmann::json doc = VerificationJson(problem, options.machine, options.order, v.result, verified.validation);
  doc["weights"] = kCmmWeights;
  doc["iterations"] = nlohmann::json::array();
  for (const stage::ResidualSummary& e : v.iterations) doc["iterations"].push_back(ErrorJson(e));
  if (verified.extraction) doc["extraction"] = ExtractionJson(*verified.extraction);
  doc["geometric"] = TermsJson(verified.geometric);
  doc["geometric_from"] = verified.geometric_from;
  doc["datum_absorbs"] = nlohmann::json::array();
  for (const stage::FixedCoefficient& f : v.datum_absorbs) doc["datum_absorbs"].push_back({{"name", f.name}, {"reason", f.reason}});
  return doc;
}

std::string VerifyText(const MachineProblem& problem, const MachinedPieceVerifyOptions& options,
                       const MachinedPieceVerifyResult& verified) {
  const stage::MachinedPieceVerification& v = verified.verification;
  const stage::IdentificationResult& r = v.result.identified;
  std::string text = fmt::format("verified the test piece: {} points, {} {} order {}\n", problem.readings.points.size(),
                                 problem.chain.code, options.machine.basis, options.order);
  text += "  iteration      max     mean      min (um)\n";
  for (size_t i = 0; i < v.iterations.size(); ++i) {
    text += fmt::format("  {:9d} {:8.2f} {:8.2f} {:8.2f}\n", i, v.iterations[i].max_um(), v.iterations[i].mean_um(),
                        v.iterations[i].min_um());
  }
  if (verified.validation) {
    text += fmt::format("  validation ({} points): mean {:.2f} -> {:.2f} um, max {:.2f} -> {:.2f} um\n",
                        problem.validation->points.size(), verified.validation->before.mean_um(),
                        verified.validation->after.mean_um(), verified.validation->before.max_um(),
                        verified.validation->after.max_um());
  }
  std::string lost;
  for (const stage::TermRecovery& t : verified.geometric) {
    if (!t.recoverable) lost += " " + t.error + (t.partly ? "(partly)" : "");
  }
  text += fmt::format("  geometric ({}): not recovered:{}\n", verified.geometric_from, lost.empty() ? " none" : lost);
  text += fmt::format("  datum: {:.4f}, {:.4f}, {:.4f} mm; absorbs {} coefficient(s) (see --json datum_absorbs)\n",
                      r.pose.translation.x(), r.pose.translation.y(), r.pose.translation.z(), v.datum_absorbs.size());
  return text;
}

// Counts of the volumetric errors before and after in bins of a round width (about 12 bins): the report's
// histograms ([Lorente 2021] Figs. 126-127, 132-133).
report::MachineReportData::Table HistogramTable(const std::vector<report::MachineReportData::PointError>& points) {
  double top = 0;
  std::vector<double> before_um, after_um;
  for (const auto& p : points) {
    top = std::max({top, p.before_um, p.after_um});
    before_um.push_back(p.before_um);
    after_um.push_back(p.after_um);
  }
  const double width = std::max(0.5, std::ceil(top / 12.0 * 2.0) / 2.0);
  const int bins = std::max(1, static_cast<int>(std::ceil(top / width + 1e-12)));
  const std::vector<int> before = BinCounts(before_um, 0.0, width, bins), after = BinCounts(after_um, 0.0, width, bins);
  report::MachineReportData::Table t{"Histogram of the volumetric errors",
                                     "Number of points per error bin, before and after the verification.",
                                     {"error (um)", "before", "after", ""},
                                     {}};
  const int most = std::max(*std::max_element(before.begin(), before.end()), *std::max_element(after.begin(), after.end()));
  for (int b = 0; b < bins; ++b) {
    const size_t i = static_cast<size_t>(b);
    t.rows.push_back({fmt::format("{:.1f} - {:.1f}", b * width, (b + 1) * width), std::to_string(before[i]),
                      std::to_string(after[i]),
                      std::string(static_cast<size_t>(40 * before[i] / std::max(1, most)), '#') + " | " +
                          std::string(static_cast<size_t>(40 * after[i] / std::max(1, most)), '*')});
  }
  return t;
}

report::MachineReportData VerifyReport(const MachineProblem& problem, const MachinedPieceVerifyOptions& options,
                                       const MachinedPieceVerifyResult& verified) {
  const stage::MachinedPieceVerification& v = verified.verification;
  report::MachineReportData data = VerificationReport(
      fmt::format("fvm testpiece verify: {} {} order {} on {}", problem.chain.code, options.machine.basis, options.order,
                  problem.readings.source),
      kCmmWeights, problem, v.result, verified.validation);
  for (report::MachineReportData::Table& t : data.tables) {
    if (t.heading == "Tracker pose") t.heading = "Datum: the piece in the CMM frame";
  }
  report::MachineReportData::Table log{
      "Iterations", "Volumetric error after each solver iteration (0: the ideal machine at the initial datum).",
      {"iteration", "max (um)", "mean (um)", "min (um)"}, {}};
  for (size_t i = 0; i < v.iterations.size(); ++i) {
    const stage::ResidualSummary& e = v.iterations[i];
    log.rows.push_back({std::to_string(i), fmt::format("{:.2f}", e.max_um()), fmt::format("{:.2f}", e.mean_um()),
                        fmt::format("{:.2f}", e.min_um())});
  }
  data.tables.insert(data.tables.begin(), log);
  data.tables.insert(data.tables.begin() + 1, HistogramTable(data.readings));
  report::MachineReportData::Table g{"Geometric verification",
                                     "From " + verified.geometric_from + ": each error at the far end of its axis.",
                                     {"error", "recoverable", "value (um or urad)", "u", "why not"}, {}};
  for (const stage::TermRecovery& t : verified.geometric) {
    g.rows.push_back({t.error, t.recoverable ? "yes" : t.partly ? "partly" : "no", fmt::format("{:.2f}", t.value),
                      fmt::format("{:.2f}", t.u), t.reason});
  }
  data.tables.push_back(g);
  return data;
}

}  // namespace

Summary SummarizeDesign(const artefacts::MachinedPieceDescription& piece, const std::vector<artefacts::PiecePoint>& points,
                        const std::string& nominal_file) {
  std::map<std::string, int> per_series, per_kind;
  for (const artefacts::PiecePoint& p : points) {
    if (IsSeries(p.series)) ++per_series[p.series];
    ++per_kind[std::string(artefacts::FeatureKindName(p.kind))];
  }
  Summary s;
  s.json = nlohmann::json{{"points", points.size()}, {"features", piece.features.size()},
            {"envelope_mm", {piece.envelope.x(), piece.envelope.y(), piece.envelope.z()}},
            {"series", per_series}, {"points_by_kind", per_kind}};
  s.text = fmt::format("test piece {:.0f} x {:.0f} x {:.0f} mm: {} features, {} probe points{}\n", piece.envelope.x(),
                       piece.envelope.y(), piece.envelope.z(), piece.features.size(), points.size(),
                       nominal_file.empty() ? "" : " -> " + nominal_file);
  for (const auto& [kind, n] : per_kind) s.text += fmt::format("  {:<13} {:4d} points\n", kind, n);
  std::string series;
  for (const auto& [name, n] : per_series) series += fmt::format(" {}:{}", name, n);
  s.text += fmt::format("  series{}\n", series);
  return s;
}

Summary Summarize(const MachineProblem& problem, const MachinedPieceVerifyOptions& options,
                  const MachinedPieceVerifyResult& verified) {
  return {VerifyJson(problem, options, verified), VerifyText(problem, options, verified),
          VerifyReport(problem, options, verified)};
}

}  // namespace fvm::workflows
