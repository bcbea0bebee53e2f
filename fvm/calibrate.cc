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
                      const std::string& shown_what) {
  ReportData data;
  data.title = fmt::format("fvm calibrate: model {} on {}", r.calibration.model, args.batch);
  const stage::ValidationStats before = stage::Validate(nullptr, shown.observations, shown.anchors);
  const stage::ValidationStats after = stage::Validate(&r.calibration, shown.observations, shown.anchors);
  data.summary = {{"model", r.calibration.model},
                  {"free parameters", std::to_string(r.calibration.layout.NumFree())},
                  {"fixed (not identifiable)", std::to_string(r.fixed.size())},
                  {"identification rms", fmt::format("{:.2f} um", r.rms_mm * 1e3)},
                  {"shown data", shown_what},
                  {"error before (mean / max)", fmt::format("{:.1f} / {:.1f} um", before.mean_mm * 1e3, before.max_mm * 1e3)},
                  {"error after (mean / max)", fmt::format("{:.2f} / {:.2f} um", after.mean_mm * 1e3, after.max_mm * 1e3)},
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
  doc["identification"]["placements"] = batch.identify;
  const stage::ValidationStats id_before = stage::Validate(nullptr, identify.observations, identify.anchors);
  doc["identification"]["before_mean_um"] = id_before.mean_mm * 1e3;
  std::optional<stage::MeasurementSet> validate;
  if (!batch.validate.empty()) {
    validate = artefacts::Observations(batch, batch.validate);
    const stage::ValidationStats before = stage::Validate(nullptr, validate->observations, validate->anchors);
    const stage::ValidationStats after = stage::Validate(&result.calibration, validate->observations, validate->anchors);
    doc["validation"] = StatsJson(after);
    doc["validation"]["placements"] = batch.validate;
    doc["validation"]["before"] = StatsJson(before);
    doc["validation"]["distance_error_max_um"] = {
        {"before", MaxAbs(stage::DistanceErrors(nullptr, validate->observations)) * 1e3},
        {"after", MaxAbs(stage::DistanceErrors(&result.calibration, validate->observations)) * 1e3}};
  }
  if (!args.output.empty()) WriteFileAtomically(args.output, doc.dump(2) + "\n");
  if (!args.report.empty()) {
    const stage::MeasurementSet& shown = validate ? *validate : identify;
    WriteReport(args.report, MakeReport(args, result, shown, validate ? "validation placements" : "identification placements"));
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
    fmt::print("  {:<34} {:>8.2f} {:>8.2f} {:>8.2f}\n", fmt::format("validation ({} centres), before", v["centres"].get<int>()),
               v["before"]["mean_um"].get<double>(), v["before"]["rms_um"].get<double>(), v["before"]["max_um"].get<double>());
    fmt::print("  {:<34} {:>8.2f} {:>8.2f} {:>8.2f}   (predicted rms {:.2f})\n", "validation, after",
               v["mean_um"].get<double>(), v["rms_um"].get<double>(), v["max_um"].get<double>(),
               v["predicted_rms_um"].get<double>());
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
