// fvm calibrate BATCH --model 9|15|27|42 -o CAL.json: identify the stage model from a batch of pairs.

#include <fmt/core.h>

#include <cmath>
#include <filesystem>
#include <optional>

#include "core/file_io.h"
#include "artefacts/io/batch.h"
#include "artefacts/io/raw_export_batch.h"
#include "core/input_error.h"
#include "stage/io/calibration_file.h"
#include "core/exit_codes.h"
#include "fvm/identify_options.h"
#include "workflows/calibrate.h"
#include "workflows/calibration_scans.h"
#include "artefacts/scan_observations.h"
#include "stage/calibration.h"
#include "fvm/commands.h"
#include "fvm/distortion_options.h"
#include "workflows/field_distortion_file.h"
#include "workflows/scan_distortion.h"
#include "report/stage_report.h"
#include "stage/validation.h"

namespace fvm::cli {
namespace {

struct CalibrateArgs {
  std::string batch;
  std::vector<std::string> scans;  // stitched calibration scans instead of a batch
  double pixel_mm = 0.0, pixel_u_mm = 0.0;
  std::string validate;            // --scan: an artefact batch whose validation placements judge the result
  workflows::ModelChoice model;
  std::string output;
  std::string report;
  std::string artefact = "bar17";  // a batch of raw exports: the artefact whose calottes are searched
  std::string centres_dir;         // ... and where the centre exports found go
  bool json = false;
  workflows::IdentifySettings settings;
  DistortionArgs distortion;  // --scan: the objective's field distortion
};

nlohmann::json StatsJson(const stage::ValidationStats& s) {
  return {{"centres", s.count}, {"mean_um", s.mean_mm * 1e3}, {"rms_um", s.rms_mm * 1e3}, {"max_um", s.max_mm * 1e3},
          {"predicted_rms_um", s.predicted_rms_mm * 1e3}, {"predicted_undetermined_rms_um", s.undetermined_rms_mm * 1e3}};
}

nlohmann::json FrameFreeJson(const stage::FrameFreeStats& s) {
  return {{"count", s.count}, {"rms_um", s.rms_mm * 1e3}, {"max_um", s.max_mm * 1e3}, {"predicted_rms_um", s.predicted_rms_mm * 1e3}};
}

using workflows::BeforeAfter;
using workflows::Judgement;

// What the first-tile figure did with each measurement's turn, for people.
std::string TurnText(const stage::ValidationStats& s, stage::StitchedFrame frame) {
  if (s.turn == "model") return "each placement turned by the model's " + JoinNames(s.turn_coefficients);
  if (s.turn == "uncertainty") {
    return fmt::format("the model cannot tell the turn, so the prediction carries its spread over the placements "
                       "({:.1f} urad about z)", s.turn_u_rad.z() * 1e6);
  }
  return frame == stage::StitchedFrame::kTranslated ? "no turn" : "no model, no turn";
}

nlohmann::json ValidationJson(const Judgement& before, const Judgement& after, stage::StitchedFrame frame) {
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

report::ReportData MakeReport(const CalibrateArgs& args, const std::string& source, const stage::IdentificationResult& r,
                      const stage::MeasurementSet& shown, const std::string& shown_what, const BeforeAfter& judged) {
  report::ReportData data;
  data.title = fmt::format("fvm calibrate: model {} on {}", r.calibration.model, source);
  const stage::StitchedFrame frame = args.settings.Frame();
  const Judgement& judged_after = judged.after;
  const stage::ValidationStats& before = judged.before.first_tile;
  const stage::ValidationStats& after = judged_after.first_tile;
  const auto frame_free = [](const stage::FrameFreeStats& s) {
    return fmt::format("{:.2f} rms / {:.2f} max um (predicted rms {:.2f})", s.rms_mm * 1e3, s.max_mm * 1e3, s.predicted_rms_mm * 1e3);
  };
  data.summary = {{"model", r.calibration.model},
                  {"free parameters", std::to_string(r.calibration.layout.NumFree())},
                  {"fixed (not identifiable)", std::to_string(r.fixed.size())},
                  {"identification rms", fmt::format("{:.2f} um", r.residual_summary.rms_um())},
                  {"shown data", shown_what},
                  {"rigid fit per placement, after", frame_free(judged_after.rigid)},
                  {"distances, all pairs, after", frame_free(judged_after.distances)},
                  {"first tile, before (mean / max)", fmt::format("{:.1f} / {:.1f} um", before.mean_mm * 1e3, before.max_mm * 1e3)},
                  {"first tile, after (mean / max)", fmt::format("{:.2f} / {:.2f} um (predicted rms {:.2f})", after.mean_mm * 1e3,
                                                                 after.max_mm * 1e3, after.predicted_rms_mm * 1e3)},
                  {"first-tile frame", fmt::format("{}: {}", stage::StitchedFrameName(frame), TurnText(after, frame))},
                  {"condition number", fmt::format("{:.3g}", r.condition_number)}};
  for (double e : judged.distance_errors_before_mm) data.distance_errors_before_um.push_back(e * 1e3);
  for (double e : judged.distance_errors_after_mm) data.distance_errors_after_um.push_back(e * 1e3);
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

// The validation rows of the table, from the JSON that scripts get.
void PrintValidation(const nlohmann::json& v) {
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

// The validation block of the JSON: held-out placements before and after, in the given frame.
nlohmann::json ValidationDocument(const BeforeAfter& judged, stage::StitchedFrame frame) {
  nlohmann::json v = ValidationJson(judged.before, judged.after, frame);
  v["distance_error_max_um"] = {{"before", MaxAbs(judged.distance_errors_before_mm) * 1e3},
                                {"after", MaxAbs(judged.distance_errors_after_mm) * 1e3}};
  return v;
}

void RunScans(const CalibrateArgs& args);

// A batch of centre exports, or of surfaces searched for calottes (artefacts/io/raw_export_batch.h): the centres
// found go as a CSV batch into --centres-dir, else REPORT/centres, else beside -o (never into the batch itself).
artefacts::Batch ReadBatchArgument(const CalibrateArgs& args, nlohmann::json& doc) {
  if (!artefacts::HoldsRawExports(args.batch)) return artefacts::ReadBatch(args.batch);
  const artefacts::RawExportBatch raw = artefacts::ReadRawExportBatch(args.batch, {args.artefact});
  std::filesystem::path dir = args.centres_dir;
  if (dir.empty() && !args.report.empty()) dir = std::filesystem::path(args.report) / "centres";
  if (dir.empty() && !args.output.empty()) dir = std::filesystem::path(args.output).replace_extension(".centres");
  if (!dir.empty()) artefacts::WriteRawExportCentres(dir, raw);
  doc["centres_dir"] = dir.empty() ? nlohmann::json(nullptr) : nlohmann::json(dir.string());
  for (const artefacts::RawExportFit& fit : raw.fits) {
    doc["exports"].push_back({{"file", fit.file.string()}, {"calottes", fit.centres.centres.size()}, {"rejected", fit.rejected}});
    if (!args.json) fmt::print("{}: {} calottes of {} found\n", fit.file.string(), fit.centres.centres.size(), args.artefact);
  }
  if (!args.json) fmt::print("{}\n\n", dir.empty() ? "centre exports not written (give --centres-dir DIR to keep them)"
                                                    : "centre exports written to " + dir.string());
  return raw.batch;
}

void Run(const CalibrateArgs& args) {
  if (args.batch.empty() == args.scans.empty()) {
    throw CLI::ValidationError("BATCH", "give a BATCH directory, or stitched calibration scans with --scan LAYOUT (not both)");
  }
  if (!args.scans.empty()) return RunScans(args);
  if (!args.validate.empty()) throw CLI::ValidationError("--validate", "is for --scan: a batch validates on its own placements");
  if (args.distortion.Requested() || !args.distortion.save.empty()) {
    throw CLI::ValidationError("--distortion", "is for --scan: a batch of centre exports holds no tiles to see a field in");
  }
  nlohmann::json raw;
  const artefacts::Batch batch = ReadBatchArgument(args, raw);
  const workflows::BatchCalibration c =
      workflows::CalibrateBatch(batch, {args.model, Threaded(args.settings), !args.report.empty()});
  const stage::IdentificationResult& result = c.result;

  nlohmann::json doc = stage::CalibrationToJson(result);
  if (!raw.is_null()) doc["raw_exports"] = raw;
  doc["batch"] = args.batch;
  doc["anchor"] = args.settings.anchor;
  doc["stitched_frame"] = args.settings.stitched_frame;
  doc["identification"]["placements"] = batch.identify;
  const stage::ValidationStats& id_before = c.identification_before;
  doc["identification"]["before_mean_um"] = id_before.mean_mm * 1e3;
  const std::optional<stage::MeasurementSet>& validate = c.validation;
  const stage::StitchedFrame frame = args.settings.Frame();
  if (validate) {
    doc["validation"] = ValidationDocument(*c.judged, frame);
    doc["validation"]["placements"] = batch.validate;
  }
  if (!args.output.empty()) WriteFileAtomically(args.output, doc.dump(2) + "\n");
  if (!args.report.empty()) {
    report::WriteReport(args.report, MakeReport(args, args.batch, result, c.Shown(),
                                        validate ? "validation placements" : "identification placements", *c.judged));
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
  fmt::print("  {:<34} {:>8.2f} {:>8.2f} {:>8.2f}\n", "identification, after", result.residual_summary.mean_um(), result.residual_summary.rms_um(),
             result.residual_summary.max_um());
  if (validate) PrintValidation(doc["validation"]);
  if (!args.output.empty()) fmt::print("\ncalibration written to {}\n", args.output);
  if (!args.report.empty()) fmt::print("report written to {}/index.html\n", args.report);
  FailIfNotConverged(result);
}

void RunScans(const CalibrateArgs& args) {
  if (!(args.pixel_mm > 0.0) || !std::isfinite(args.pixel_mm)) {
    throw InputError("--scan needs --pixel-mm: the size of a camera pixel on the part (mm), e.g. 0.00275 for the 5x "
                     "lens's 2.82 mm field on 1024 px; it sets the scale of every registered offset");
  }
  if (!(args.pixel_u_mm >= 0.0) || !std::isfinite(args.pixel_u_mm)) throw InputError("--pixel-u-mm: give a standard uncertainty >= 0 (mm)");
  args.distortion.Check();
  std::optional<workflows::ScanDistortion> field;
  std::vector<artefacts::RegisteredScan> scans;
  if (args.distortion.Requested()) {
    workflows::ScanDistortionOptions distortion_options;
    distortion_options.order = args.distortion.Order();
    distortion_options.known = args.distortion.Known();
    field.emplace();
    scans = workflows::ReadAndRegisterUndistortedScans(args.scans, args.pixel_mm, ThreadCount(), ShowProgress(),
                                                       distortion_options, &*field);
    if (!args.distortion.save.empty()) workflows::WriteFieldDistortion(args.distortion.save, field->fit.field, args.pixel_mm);
  } else {
    scans = workflows::ReadAndRegisterScans(args.scans, args.pixel_mm, ThreadCount(), ShowProgress());
  }
  std::optional<artefacts::Batch> validation_batch;
  if (!args.validate.empty()) validation_batch = artefacts::ReadBatch(args.validate);
  workflows::ScanCalibrationResult scan_result = workflows::CalibrateScans(
      scans, {args.model, Threaded(args.settings), args.pixel_mm, args.pixel_u_mm}, validation_batch ? &*validation_batch : nullptr);
  stage::IdentificationResult& result = scan_result.fitted.result;
  const artefacts::ScanResidualSplit& split = scan_result.fitted.split;
  stage::Calibration& cal = result.calibration;
  const double without_pixel_um = scan_result.predicted_without_pixel_um;
  const double predicted_um = scan_result.predicted_xy_um;

  nlohmann::json doc = stage::CalibrationToJson(result);
  doc["stitched_frame"] = args.settings.stitched_frame;
  doc["pixel_mm"] = args.pixel_mm;
  doc["pixel_u_mm"] = args.pixel_u_mm;
  if (field) doc["distortion"] = DistortionJson(field->fit, field->identified, args.pixel_mm);
  int tiles = 0, pairs = 0, registered = 0;
  for (const auto& scan : scans) {
    nlohmann::json j = {{"name", scan.name}, {"tiles", scan.encoder_mm.size()}, {"pairs", scan.registration.pairs.size()},
                        {"searched_again", scan.registration.pairs_searched_again}};
    int ok = 0;
    for (const auto& pair : scan.registration.pairs) {
      if (pair.accepted) {
        ++ok;
      } else {
        j["rejected"].push_back({{"tiles", {pair.a + 1, pair.b + 1}}, {"reason", pair.rejection}});
      }
    }
    j["registered"] = ok;
    tiles += static_cast<int>(scan.encoder_mm.size());
    pairs += static_cast<int>(scan.registration.pairs.size());
    registered += ok;
    doc["scans"].push_back(j);
  }
  // What no image of a scan can tell, whatever the rank analysis finds on these data (it takes the pixel size as
  // given): the scale of the pixels, and the camera's turn against the stage axes.
  doc["cannot_tell"] = {
      {{"what", "the pixel size"}, {"aliases", {"xTx1", "yTy1"}},
       {"fixed_by", "--pixel-mm (its uncertainty --pixel-u-mm propagates), or one known length"}},
      {{"what", "the camera's rotation against the stage axes"}, {"aliases", {"xRz0", "yRz0", "xWy0"}},
       {"fixed_by", "the first tile's frame: the result is in it (stitched_frame.h), as an artefact calibration's is"}}};
  const double misfit_um = split.misfit_mm * 1e3;
  doc["predicted_xy_u_um"] = {{"pair_weights", predicted_um},
                              {"pair_weights_without_pixel_size", without_pixel_um},
                              {"independent_positions", scan_result.predicted_independent_um},
                              {"model_misfit_along_scans", misfit_um},
                              {"combined", scan_result.predicted_xy_with_misfit_um},
                              {"white_residual_ratio", split.white_ratio},
                              {"what", "standard uncertainty of the xy stage error, rms over the box the scans cover, "
                                       "less the offset and the turn about z no registered image can tell: from the "
                                       "coefficients' covariance (pair weights, the white part of the residuals, the "
                                       "registrations' sub-pixel bias, the misfit the coefficients took up), and what "
                                       "the model leaves along the scans (misfit), combined"}};
  const std::optional<stage::MeasurementSet>& validate = scan_result.validation;
  const std::optional<BeforeAfter>& judged = scan_result.judged;
  if (judged) {
    doc["validation"] = ValidationDocument(*judged, args.settings.Frame());
    doc["validation"]["batch"] = args.validate;
    doc["validation"]["note"] = "grey tiles show no heights: z terms stay at 0; the 3-D figures keep the stage's z errors, the distances hardly see them";
    doc["validation"]["placements"] = scan_result.validation_placements;
  }
  const std::string source = fmt::format("{} scans ({})", scans.size(), JoinNames(args.scans));
  if (!args.output.empty()) WriteFileAtomically(args.output, doc.dump(2) + "\n");
  if (!args.report.empty()) {
    if (!judged) throw InputError("--report with --scan needs --validate BATCH: the report shows held-out placements");
    report::WriteReport(args.report, MakeReport(args, source, result, *validate, "validation placements of " + args.validate, *judged));
  }
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
    FailIfNotConverged(result);
    return;
  }
  fmt::print("fvm calibrate: model {} ({} chain, eq. 1) on {}\n", cal.model, cal.layout.chain().code, source);
  for (const auto& j : doc["scans"]) {
    fmt::print("  {}: {} tiles, {} of {} neighbour pairs registered\n", j["name"].get<std::string>(), j["tiles"].get<int>(),
               j["registered"].get<int>(), j["pairs"].get<int>());
    if (j.contains("rejected")) {
      for (const auto& r : j["rejected"]) {
        fmt::print("    tiles {}-{} not used: {}\n", r["tiles"][0].get<int>(), r["tiles"][1].get<int>(), r["reason"].get<std::string>());
      }
    }
  }
  fmt::print("  {} tiles, {} of {} pairs registered; pixel {:.6g} mm (u {:.2g} mm); frame: the first tile of {}, {}\n", tiles,
             registered, pairs, args.pixel_mm, args.pixel_u_mm, scans.front().name, args.settings.stitched_frame);
  if (field) fmt::print("{}", DistortionText(field->fit, field->identified, args.pixel_mm));
  fmt::print("  solver: {} in {} iterations; condition number {:.3g}\n", result.converged ? "converged" : "NOT converged",
             result.iterations, result.condition_number);
  PrintParameters(result);
  fmt::print("\n  no scan can tell the pixel size from xTx1, yTy1 (taken from --pixel-mm), nor the camera's turn against\n"
             "  the stage axes from the constant yaw and squareness xRz0, yRz0, xWy0 (the result is in the first tile's frame)\n");
  fmt::print("\n  registered displacements after the fit: rms {:.3f} um (weighted rms {:.2f}: 1 = as the registrations' own "
             "covariances say)\n", result.residual_summary.rms_um(), result.weighted_rms);
  fmt::print("  the residuals' white part is {:.2f} x the registrations' covariance; chained along the scans they leave "
             "{:.3f} um rms that the model cannot take\n", split.white_ratio, misfit_um);
  fmt::print("  predicted xy stage-error uncertainty over the scanned box, less its offset and turn about z (k=1): {:.3f} um rms "
             "from the coefficients", predicted_um);
  if (args.pixel_u_mm > 0.0) fmt::print(" ({:.3f} um without the pixel size's)", without_pixel_um);
  fmt::print(", {:.3f} um with the misfit\n", scan_result.predicted_xy_with_misfit_um);
  fmt::print("  the same positions as independent points of equal weight: {:.3f} um (the chain's correlation ignored)\n",
             doc["predicted_xy_u_um"]["independent_positions"].get<double>());
  if (validate) {
    PrintValidation(doc["validation"]);
    fmt::print("  grey tiles show no heights: the scans leave the z terms at 0, so the 3-D figures above keep the stage's\n"
               "  z errors; the distances, which z hardly changes on a flat artefact, judge the scan calibration\n");
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
                                        "optional batch.json {\"identify\": [...], \"validate\": [...]}");
  sub->add_option("--scan", args->scans,
                   "instead of a batch: a stitched calibration scan of any textured part (repeat: row, column, "
                   "diagonal; fvm tiles plan --calibration-scan): layout CSV file,row,col,x,y[,z] in scan order, x,y,z "
                   "the encoder reading of each tile's centre (mm), tiles grey 8/16-bit images. Each pair of "
                   "neighbours registered is a displacement the stage model must explain, turned with the stage; a "
                   "scan cannot tell the pixel size from xTx1, yTy1 (give --pixel-mm) nor constant offsets and turns, "
                   "and a scan at one height cannot tell pitch and roll (scan again at a second height)");
  sub->add_option("--pixel-mm", args->pixel_mm, "--scan: the pixel size on the part (mm): the scale of every offset")
      ->check(Within(kPixelMm));
  sub->add_option("--pixel-u-mm", args->pixel_u_mm, "--scan: its standard uncertainty (mm), propagated into the result")
      ->check(Within(0.0, 0.1, "mm"));
  AddDistortionOptions(sub, &args->distortion, false);
  sub->add_option("--validate", args->validate,
                  "--scan: an artefact batch of the same stage; its validation placements (all, without batch.json) "
                  "judge the scan calibration as they judge a batch's");
  sub->add_option("--model", args->model.model, "[Pérez 2019] model: 9 (eq. 15), 15 (order 0), 27 (order 1), 42 (order 2)")
      ->check(CLI::IsMember({"9", "15", "27", "42"}))
      ->capture_default_str();
  sub->add_option("--terms", args->model.terms,
                  "compose your own model instead: TERM[:BASIS][:ORDER],... e.g. 'xTx:legendre:2,yRz:1,xWy' "
                  "(VDI 2617-3 names; bases power, legendre, chebyshev; orders 0..3)");
  sub->add_option("-o,--output", args->output, "write the calibration (JSON, mm and rad) here");
  sub->add_option("--report", args->report, "write an HTML report with plots into this directory");
  sub->add_option("--artefact", args->artefact,
                  "a BATCH of surfaces (<placement>.stitched.x3p / .free.x3p, also .al3d .sdf .tif): the artefact "
                  "whose calottes are searched and numbered as 'fvm fit --artefact' does, e.g. --artefact grid6x6")
      ->capture_default_str();
  sub->add_option("--centres-dir", args->centres_dir,
                  "a BATCH of surfaces: write the centre exports found here as a CSV batch (default REPORT/centres, "
                  "else beside -o as CAL.centres), e.g. --centres-dir centres");
  sub->add_flag("--json", args->json, "print the calibration JSON on stdout instead of the table");
  AddIdentifyOptions(*sub, args->settings);
  sub->footer("Exit 3 when the solver did not converge (the calibration is still written).\n"
              "Examples:\n  fvm calibrate samples/bar17 --model 27 -o stage.json\n"
              "  fvm calibrate raw --model 27 -o stage.json --report report   # raw/ holds P.stitched.x3p, P.free.x3p\n"
              "  fvm calibrate --scan s/row.csv --scan s/column.csv --scan s/diagonal.csv --pixel-mm 0.00275 --model 27 "
              "-o stage.json --validate samples/bar17");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
