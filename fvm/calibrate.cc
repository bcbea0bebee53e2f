// fvm calibrate BATCH --model 9|15|27|42 -o CAL.json: identify the stage model from a batch of pairs.

#include <fmt/core.h>

#include <cmath>

#include "core/file_io.h"
#include "artefacts/io/batch.h"
#include "core/input_error.h"
#include "stage/io/calibration_file.h"
#include "core/exit_codes.h"
#include "fvm/calibration_run.h"
#include "fvm/commands.h"
#include "fvm/report.h"
#include "stage/validation.h"

namespace fvm::cli {
namespace {

struct CalibrateArgs {
  std::string batch;
  std::string model = "27";
  std::string terms;
  std::string output;
  std::string report;
  bool json = false;
  IdentifySettings settings;
};

nlohmann::json StatsJson(const stage::ValidationStats& s) {
  return {{"centres", s.count}, {"mean_um", s.mean_mm * 1e3}, {"rms_um", s.rms_mm * 1e3}, {"max_um", s.max_mm * 1e3},
          {"predicted_rms_um", s.predicted_rms_mm * 1e3}};
}

nlohmann::json FrameFreeJson(const stage::FrameFreeStats& s) {
  return {{"count", s.count}, {"rms_um", s.rms_mm * 1e3}, {"max_um", s.max_mm * 1e3}, {"predicted_rms_um", s.predicted_rms_mm * 1e3}};
}

// A calibration judged on held-out measurements: first what no frame changes, then the first-tile figure.
struct Judged {
  stage::FrameFreeStats rigid, distances;
  stage::ValidationStats first_tile;
};
Judged Judge(const stage::Calibration* calibration, const stage::MeasurementSet& set, stage::StitchedFrame frame) {
  return {stage::RigidValidation(calibration, set.observations), stage::PairDistanceValidation(calibration, set.observations),
          stage::Validate(calibration, set.observations, set.anchors, frame)};
}

// The shown measurements without compensation and with the calibration: what the JSON and the report quote.
struct BeforeAfter {
  Judged before, after;
};

// What the first-tile figure did with each measurement's turn, for people.
std::string TurnText(const stage::ValidationStats& s, stage::StitchedFrame frame) {
  if (s.turn == "model") return "each placement turned by the model's " + JoinNames(s.turn_coefficients);
  if (s.turn == "uncertainty") {
    return fmt::format("the model cannot tell the turn, so the prediction carries its spread over the placements "
                       "({:.1f} urad about z)", s.turn_u_rad.z() * 1e6);
  }
  return frame == stage::StitchedFrame::kTranslated ? "no turn" : "no model, no turn";
}

nlohmann::json ValidationJson(const Judged& before, const Judged& after, stage::StitchedFrame frame) {
  nlohmann::json v = StatsJson(after.first_tile);
  v["rigid"] = FrameFreeJson(after.rigid);
  v["distances"] = FrameFreeJson(after.distances);
  v["stitched_frame"] = stage::StitchedFrameName(frame);
  v["turn"] = after.first_tile.turn;
  v["turn_note"] = TurnText(after.first_tile, frame);
  v["turn_coefficients"] = after.first_tile.turn_coefficients;
  const Eigen::Vector3d& u = after.first_tile.turn_u_rad;
  v["turn_u_urad"] = {u.x() * 1e6, u.y() * 1e6, u.z() * 1e6};
  v["before"] = StatsJson(before.first_tile);
  v["before"]["rigid"] = FrameFreeJson(before.rigid);
  v["before"]["distances"] = FrameFreeJson(before.distances);
  return v;
}

double MaxAbs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

void PrintParameters(const stage::IdentificationResult& r) {
  const stage::Calibration& cal = r.calibration;
  const Eigen::VectorXd u = cal.StandardUncertainty();
  fmt::print("\n  {:<8} {:>12} {:>10}   {}\n", "param", "value", "u (k=1)", "unit");
  for (const std::string& name : cal.layout.FreeNames()) {
    const int slot = cal.layout.FreeIndexOf(name);
    const auto& c = cal.layout.coefficients()[static_cast<size_t>(cal.layout.FindCoefficient(name))];
    const stage::DisplayUnit unit = stage::UnitOf(c);
    fmt::print("  {:<8} {:>12.3f} {:>10.3f}   {}\n", name, cal.values[static_cast<size_t>(slot)] * unit.per_si,
               u[slot] * unit.per_si, unit.name);
  }
  if (!r.fixed.empty()) {
    fmt::print("\n  fixed at 0 (the data cannot determine them):\n");
    for (const stage::FixedCoefficient& f : r.fixed) fmt::print("  {:<8} {}\n", f.name, f.reason);
  }
}

ReportData MakeReport(const CalibrateArgs& args, const stage::IdentificationResult& r, const stage::MeasurementSet& shown,
                      const std::string& shown_what, const BeforeAfter& judged) {
  ReportData data;
  data.title = fmt::format("fvm calibrate: model {} on {}", r.calibration.model, args.batch);
  const stage::StitchedFrame frame = args.settings.Frame();
  const Judged& judged_after = judged.after;
  const stage::ValidationStats& before = judged.before.first_tile;
  const stage::ValidationStats& after = judged_after.first_tile;
  const auto frame_free = [](const stage::FrameFreeStats& s) {
    return fmt::format("{:.2f} rms / {:.2f} max um (predicted rms {:.2f})", s.rms_mm * 1e3, s.max_mm * 1e3, s.predicted_rms_mm * 1e3);
  };
  data.summary = {{"model", r.calibration.model},
                  {"free parameters", std::to_string(r.calibration.layout.NumFree())},
                  {"fixed (not identifiable)", std::to_string(r.fixed.size())},
                  {"identification rms", fmt::format("{:.2f} um", r.rms_mm * 1e3)},
                  {"shown data", shown_what},
                  {"rigid fit per placement, after", frame_free(judged_after.rigid)},
                  {"distances, all pairs, after", frame_free(judged_after.distances)},
                  {"first tile, before (mean / max)", fmt::format("{:.1f} / {:.1f} um", before.mean_mm * 1e3, before.max_mm * 1e3)},
                  {"first tile, after (mean / max)", fmt::format("{:.2f} / {:.2f} um (predicted rms {:.2f})", after.mean_mm * 1e3,
                                                                 after.max_mm * 1e3, after.predicted_rms_mm * 1e3)},
                  {"first-tile frame", fmt::format("{}: {}", stage::StitchedFrameName(frame), TurnText(after, frame))},
                  {"condition number", fmt::format("{:.3g}", r.condition_number)}};
  for (double e : stage::DistanceErrors(nullptr, shown.observations)) data.distance_errors_before_um.push_back(e * 1e3);
  for (double e : stage::DistanceErrors(&r.calibration, shown.observations)) data.distance_errors_after_um.push_back(e * 1e3);
  for (size_t i = 0; i < shown.observations.size(); ++i) {
    const Eigen::Vector3d& q = shown.observations[i].command;
    data.errors_before.push_back({q.x(), q.y(), -before.residuals[i].x() * 1e3, -before.residuals[i].y() * 1e3});
    data.errors_after.push_back({q.x(), q.y(), -after.residuals[i].x() * 1e3, -after.residuals[i].y() * 1e3});
  }
  const Eigen::VectorXd u = r.calibration.StandardUncertainty();
  for (const std::string& name : r.calibration.layout.FreeNames()) {
    const int slot = r.calibration.layout.FreeIndexOf(name);
    const auto& c = r.calibration.layout.coefficients()[static_cast<size_t>(r.calibration.layout.FindCoefficient(name))];
    const stage::DisplayUnit unit = stage::UnitOf(c);
    data.parameters.push_back({name, r.calibration.values[static_cast<size_t>(slot)] * unit.per_si, u[slot] * unit.per_si, unit.name});
  }
  return data;
}

// Exit 3 after everything is written and printed: a script must not take an unconverged calibration as done.
void FailIfNotConverged(const stage::IdentificationResult& result) {
  if (!result.converged) {
    throw NotConvergedError(fmt::format("model {}: the solver stopped after {} iterations without converging; the "
                                        "calibration was written but do not use it: check the batch for outliers or "
                                        "try --loss huber",
                                        result.calibration.model, result.iterations));
  }
}

void Run(const CalibrateArgs& args) {
  const artefacts::Batch batch = artefacts::ReadBatch(args.batch);
  const stage::MeasurementSet identify = artefacts::Observations(batch, batch.identify);
  const stage::IdentificationResult result = IdentifyModel(args.model, args.terms, identify, args.settings);

  nlohmann::json doc = stage::CalibrationToJson(result);
  doc["batch"] = args.batch;
  doc["anchor"] = args.settings.anchor;
  doc["stitched_frame"] = args.settings.stitched_frame;
  doc["identification"]["placements"] = batch.identify;
  const stage::ValidationStats id_before = stage::Validate(nullptr, identify.observations, identify.anchors);
  doc["identification"]["before_mean_um"] = id_before.mean_mm * 1e3;
  std::optional<stage::MeasurementSet> validate;
  if (!batch.validate.empty()) validate = artefacts::Observations(batch, batch.validate);
  // Validation placements when the batch has them, else the identification ones (report only), judged once.
  const stage::MeasurementSet& shown = validate ? *validate : identify;
  const stage::StitchedFrame frame = args.settings.Frame();
  std::optional<BeforeAfter> judged;
  if (validate || !args.report.empty()) judged = BeforeAfter{Judge(nullptr, shown, frame), Judge(&result.calibration, shown, frame)};
  if (validate) {
    doc["validation"] = ValidationJson(judged->before, judged->after, frame);
    doc["validation"]["placements"] = batch.validate;
    doc["validation"]["distance_error_max_um"] = {
        {"before", MaxAbs(stage::DistanceErrors(nullptr, validate->observations)) * 1e3},
        {"after", MaxAbs(stage::DistanceErrors(&result.calibration, validate->observations)) * 1e3}};
  }
  if (!args.output.empty()) WriteFileAtomically(args.output, doc.dump(2) + "\n");
  if (!args.report.empty()) {
    WriteReport(args.report,
                MakeReport(args, result, shown, validate ? "validation placements" : "identification placements", *judged));
  }
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
    FailIfNotConverged(result);
    return;
  }

  const stage::Calibration& cal = result.calibration;
  fmt::print("fvm calibrate: model {} ({} chain, eq. 1) on {}\n", cal.model, cal.layout.chain().code, args.batch);
  fmt::print("  identification: {} ({} centres), anchor {}\n", JoinNames(batch.identify), result.residuals.size(),
             args.settings.anchor);
  fmt::print("  solver: {} in {} iterations; condition number {:.3g}\n", result.converged ? "converged" : "NOT converged",
             result.iterations, result.condition_number);
  PrintParameters(result);
  fmt::print("\n  {:<34} {:>8} {:>8} {:>8}\n", "3D centre error (um)", "mean", "rms", "max");
  fmt::print("  {:<34} {:>8.2f} {:>8.2f} {:>8.2f}\n", "identification, before", id_before.mean_mm * 1e3, id_before.rms_mm * 1e3,
             id_before.max_mm * 1e3);
  fmt::print("  {:<34} {:>8.2f} {:>8.2f} {:>8.2f}\n", "identification, after", result.mean_mm * 1e3, result.rms_mm * 1e3,
             result.max_mm * 1e3);
  if (validate) {
    const auto& v = doc["validation"];
    const auto row = [](const std::string& what, const nlohmann::json& s, const std::string& mean, bool predicted) {
      fmt::print("  {:<34} {:>8} {:>8.2f} {:>8.2f}", what, mean, s["rms_um"].get<double>(), s["max_um"].get<double>());
      fmt::print("{}\n", predicted ? fmt::format("   (predicted rms {:.2f})", s["predicted_rms_um"].get<double>()) : "");
    };
    fmt::print("  validation, {} centres; first what no choice of frame changes:\n", v["centres"].get<int>());
    row("rigid fit per placement, before", v["before"]["rigid"], "", false);
    row("rigid fit per placement, after", v["rigid"], "", true);
    row(fmt::format("distances ({} pairs), before", v["distances"]["count"].get<int>()), v["before"]["distances"], "", false);
    row("distances, after", v["distances"], "", true);
    fmt::print("  then each placement in its first tile's frame ({}: {}):\n", v["stitched_frame"].get<std::string>(),
               v["turn_note"].get<std::string>());
    row("first tile, before", v["before"], fmt::format("{:.2f}", v["before"]["mean_um"].get<double>()), false);
    row("first tile, after", v, fmt::format("{:.2f}", v["mean_um"].get<double>()), true);
    fmt::print("  largest distance error on validation: {:.1f} um before, {:.2f} um after\n",
               v["distance_error_max_um"]["before"].get<double>(), v["distance_error_max_um"]["after"].get<double>());
  }
  if (!args.output.empty()) fmt::print("\ncalibration written to {}\n", args.output);
  if (!args.report.empty()) fmt::print("report written to {}/index.html\n", args.report);
  FailIfNotConverged(result);
}

}  // namespace

void RegisterCalibrate(CLI::App& app) {
  auto args = std::make_shared<CalibrateArgs>();
  CLI::App* sub = app.add_subcommand(
      "calibrate", "identify the YXFZ stage model (9/15/27/42 parameters) from a batch of stitched / stitching-free pairs");
  sub->add_option("BATCH", args->batch, "batch directory: <placement>.stitched.csv + <placement>.free.csv pairs, "
                                        "optional batch.json {\"identify\": [...], \"validate\": [...]}")
      ->required();
  sub->add_option("--model", args->model, "published model: 9 (eq. 15), 15 (order 0), 27 (order 1), 42 (order 2)")
      ->check(CLI::IsMember({"9", "15", "27", "42"}))
      ->capture_default_str();
  sub->add_option("--terms", args->terms,
                  "compose your own model instead: TERM[:BASIS][:ORDER],... e.g. 'xTx:legendre:2,yRz:1,xWy' "
                  "(VDI 2617-3 names; bases power, legendre, chebyshev; orders 0..3)");
  sub->add_option("-o,--output", args->output, "write the calibration (JSON, mm and rad) here");
  sub->add_option("--report", args->report, "write an HTML report with plots into this directory");
  sub->add_flag("--json", args->json, "print the calibration JSON on stdout instead of the table");
  args->settings.AddOptions(*sub);
  sub->footer("Exit 3 when the solver did not converge (the calibration is still written).\n"
              "Example:\n  fvm calibrate samples/bar17 --model 27 -o stage.json");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
