// fvm calibrate BATCH --model 9|15|27|42 -o CAL.json: identify the stage model from a batch of pairs, or from
// stitched calibration scans (--scan). The job and its summary are the library's (workflows/calibrate_job.h,
// workflows/calibration_summary.h); here the options are bound, the files written and the text printed.

#include <fmt/core.h>

#include <filesystem>

#include "core/exit_codes.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "fvm/commands.h"
#include "fvm/distortion_options.h"
#include "fvm/identify_options.h"
#include "report/report.h"
#include "workflows/calibrate_job.h"
#include "workflows/calibration_summary.h"

namespace fvm::cli {
namespace {

struct CalibrateArgs {
  std::string batch;
  std::vector<std::string> scans;  // stitched calibration scans instead of a batch
  std::string output;
  std::string report;
  bool json = false;
  workflows::CalibrateJobOptions options;
  DistortionArgs distortion;  // --scan: the objective's field distortion, bound here (options.distortion as parsed)
};

// Exit 3 after everything is written and printed: a script must not take an unconverged calibration as done.
void FailIfNotConverged(const stage::IdentificationResult& result) {
  if (!result.converged) {
    throw NotConvergedError(fmt::format("model {}: the solver stopped after {} iterations without converging; the "
                                        "calibration was written but do not use it: check the batch for outliers or "
                                        "try --loss huber",
                                        result.calibration.model, result.iterations));
  }
}

// Writes -o, checks and writes the report, prints the JSON or the text with the files written.
void Finish(const CalibrateArgs& args, const workflows::Summary& summary, const stage::IdentificationResult& result) {
  if (!args.output.empty()) WriteFileAtomically(args.output, summary.json.dump(2) + "\n");
  if (!args.report.empty()) {
    if (!summary.report) throw InputError("--report with --scan needs --validate BATCH: the report shows held-out placements");
    report::Write(args.report, *summary.report);
  }
  if (args.json) {
    fmt::print("{}\n", summary.json.dump(2));
  } else {
    fmt::print("{}", summary.text);
    if (!args.output.empty()) fmt::print("\ncalibration written to {}\n", args.output);
    if (!args.report.empty()) fmt::print("report written to {}/index.html\n", args.report);
  }
  FailIfNotConverged(result);
}

// Without --centres-dir, the centres found in raw exports go into REPORT/centres, else beside -o (never into the
// batch itself).
std::string CentresDir(const CalibrateArgs& args) {
  if (!args.options.centres_dir.empty()) return args.options.centres_dir;
  if (!args.report.empty()) return (std::filesystem::path(args.report) / "centres").string();
  if (!args.output.empty()) return std::filesystem::path(args.output).replace_extension(".centres").string();
  return "";
}

void RunBatch(const CalibrateArgs& args, workflows::CalibrateJobOptions options) {
  if (!args.options.validate.empty()) throw CLI::ValidationError("--validate", "is for --scan: a batch validates on its own placements");
  if (args.distortion.Requested() || !args.distortion.save.empty()) {
    throw CLI::ValidationError("--distortion", "is for --scan: a batch of centre exports holds no tiles to see a field in");
  }
  options.centres_dir = CentresDir(args);
  options.judge_identification = !args.report.empty();
  workflows::CalibrationBatchInput input = workflows::ReadCalibrationBatch(args.batch, options);
  if (input.raw && !args.json) fmt::print("{}", workflows::RawExportsText(*input.raw, options.artefact, options.centres_dir));
  const workflows::BatchCalibrationRun run = workflows::CalibrateBatchInput(std::move(input), options);
  Finish(args, workflows::Summarize(run), run.calibration.result);
}

void Run(const CalibrateArgs& args) {
  if (args.batch.empty() == args.scans.empty()) {
    throw CLI::ValidationError("BATCH", "give a BATCH directory, or stitched calibration scans with --scan LAYOUT (not both)");
  }
  workflows::CalibrateJobOptions options = args.options;
  options.settings = Threaded(options.settings);
  options.distortion = args.distortion.Parsed();
  if (args.scans.empty()) return RunBatch(args, options);
  options.progress = ShowProgress();
  const workflows::ScanCalibrationRun run = workflows::CalibrateScanLayouts(args.scans, options);
  Finish(args, workflows::Summarize(run), run.calibration.fitted.result);
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
  sub->add_option("--pixel-mm", args->options.pixel_mm, "--scan: the pixel size on the part (mm): the scale of every offset")
      ->check(Within(kPixelMm));
  sub->add_option("--pixel-u-mm", args->options.pixel_u_mm, "--scan: its standard uncertainty (mm), propagated into the result")
      ->check(Within(0.0, 0.1, "mm"));
  AddDistortionOptions(sub, &args->distortion, false);
  sub->add_option("--validate", args->options.validate,
                  "--scan: an artefact batch of the same stage; its validation placements (all, without batch.json) "
                  "judge the scan calibration as they judge a batch's");
  sub->add_option("--model", args->options.model.model, "[Pérez 2019] model: 9 (eq. 15), 15 (order 0), 27 (order 1), 42 (order 2)")
      ->check(CLI::IsMember({"9", "15", "27", "42"}))
      ->capture_default_str();
  sub->add_option("--terms", args->options.model.terms,
                  "compose your own model instead: TERM[:BASIS][:ORDER],... e.g. 'xTx:legendre:2,yRz:1,xWy' "
                  "(VDI 2617-3 names; bases power, legendre, chebyshev; orders 0..3)");
  sub->add_option("-o,--output", args->output, "write the calibration (JSON, mm and rad) here");
  sub->add_option("--report", args->report, "write an HTML report with plots into this directory");
  sub->add_option("--artefact", args->options.artefact,
                  "a BATCH of surfaces (<placement>.stitched.x3p / .free.x3p, also .al3d .sdf .tif): the artefact "
                  "whose calottes are searched and numbered as 'fvm fit --artefact' does, e.g. --artefact grid6x6")
      ->capture_default_str();
  sub->add_option("--centres-dir", args->options.centres_dir,
                  "a BATCH of surfaces: write the centre exports found here as a CSV batch (default REPORT/centres, "
                  "else beside -o as CAL.centres), e.g. --centres-dir centres");
  sub->add_flag("--json", args->json, "print the calibration JSON on stdout instead of the table");
  AddIdentifyOptions(*sub, args->options.settings);
  sub->footer("Exit 3 when the solver did not converge (the calibration is still written).\n"
              "Examples:\n  fvm calibrate samples/bar17 --model 27 -o stage.json\n"
              "  fvm calibrate raw --model 27 -o stage.json --report report   # raw/ holds P.stitched.x3p, P.free.x3p\n"
              "  fvm calibrate --scan s/row.csv --scan s/column.csv --scan s/diagonal.csv --pixel-mm 0.00275 --model 27 "
              "-o stage.json --validate samples/bar17");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
