// fvm testpiece design|verify and fvm simulate testpiece: the machined test piece of [Lorente 2021]. The verification
// is fvm verify's (workflows/machined_piece_verify.h): a CMM-measured piece is a tracker whose pose is the piece's
// datum; the simulation is workflows/simulate_testpiece.h.

#include <fmt/core.h>

#include <filesystem>

#include "artefacts/geometry/machined_piece.h"
#include "artefacts/io/tracker_readings.h"
#include "core/exit_codes.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "fvm/summary_output.h"
#include "fvm/commands.h"
#include "fvm/machine_options.h"
#include "fvm/option_parsing.h"
#include "workflows/machined_piece_summary.h"
#include "workflows/simulate_testpiece.h"

namespace fvm::cli {
namespace {

// PIECE, the optional description both design and simulate take.
void AddPieceArgument(CLI::App* sub, std::string& piece) {
  sub->add_option("PIECE", piece, "piece description (JSON); default: the published piece of [Lorente 2021]")->check(CLI::ExistingFile);
}

struct PieceDesignCommand {
  std::string piece, output, cmm, gcode, describe;
  bool json = false;
};

void RunPieceDesign(const PieceDesignCommand& c) {
  const artefacts::MachinedPieceDescription piece =
      c.piece.empty() ? artefacts::PublishedMachinedPiece() : artefacts::ReadMachinedPiece(c.piece);
  const std::vector<artefacts::PiecePoint> points = artefacts::NominalPoints(piece);
  if (points.empty()) throw InputError(fmt::format("{}: the piece has no probe points; give each feature \"points\"", c.piece));
  if (!c.output.empty()) artefacts::WriteNominalPoints(c.output, points);
  if (!c.cmm.empty()) {
    std::filesystem::create_directories(c.cmm);
    WriteFileAtomically(std::filesystem::path(c.cmm) / "program.txt", artefacts::CmmProgram(points));
  }
  if (!c.gcode.empty()) WriteFileAtomically(c.gcode, artefacts::CuttingProgram(piece));
  if (!c.describe.empty()) WriteFileAtomically(c.describe, artefacts::MachinedPieceJson(piece));
  const workflows::Summary summary = workflows::SummarizeDesign(piece, points, c.output);
  fmt::print("{}", c.json ? summary.json.dump(2) + "\n" : summary.text);
}

struct PieceVerifyCommand {
  workflows::MachinedPieceVerifyOptions options;
  std::string report;
  bool json = false;
};

void RunPieceVerify(PieceVerifyCommand c) {
  workflows::MachinedPieceVerifyOptions& options = c.options;
  options.machine.threads = ThreadCount();
  options.Check();
  const workflows::MachineProblem problem = workflows::LoadMachineProblem(options.machine);
  const workflows::MachinedPieceVerifyResult verified = workflows::VerifyMachinedPiece(problem, options);
  workflows::Summary summary = workflows::Summarize(problem, options, verified);
  AddSortedPath(summary.json, "data", options.machine.data);
  if (!c.report.empty()) report::Write(c.report, *summary.report);
  fmt::print("{}", c.json ? summary.json.dump(2) + "\n" : summary.text);
  const stage::IdentificationResult& r = verified.verification.result.identified;
  if (!r.converged) throw NotConvergedError(workflows::NotConvergedReason(r));
}

struct PieceSimulateCommand {
  workflows::SimulateTestPieceOptions options;
  std::string output;
  bool json = false;
};

void RunPieceSimulate(const PieceSimulateCommand& c) {
  c.options.Check();
  const workflows::SimulatedTestPiece simulated = workflows::SimulateTestPiece(c.options);
  workflows::WriteFiles(simulated, c.output);
  workflows::Summary summary = workflows::Summarize(simulated, c.options, c.output);
  AddSortedPath(summary.json, "output", c.output);
  fmt::print("{}", c.json ? summary.json.dump(2) + "\n" : summary.text);
}

}  // namespace

void RegisterTestPiece(CLI::App& app) {
  CLI::App* tp = app.add_subcommand("testpiece", "the machined test piece of [Lorente 2021]: design it, verify a machine from its CMM measurement");
  tp->require_subcommand(1);
  tp->footer("Examples:\n  fvm testpiece design -o nominal.csv --gcode piece.nc --cmm cmm\n"
             "  fvm simulate testpiece -o tp && fvm testpiece verify tp/measured.csv --basis chebyshev --order 2");

  auto design = std::make_shared<PieceDesignCommand>();
  CLI::App* d = tp->add_subcommand("design", "nominal probe points of a test piece (that of [Lorente 2021] without PIECE.json)");
  AddDetails(d,
             "Writes NOMINAL.csv id,x,y,z,series: machine coordinates (mm) of every probe point, `series` naming X1..X3, "
             "Y1..Y3, Z1..Z3 (the geometric verification's series) or else the feature. A PIECE.json describes the envelope "
             "and features as boxes with probe points (format: docs/commands/testpiece.md); features that collide "
             "or leave the envelope are refused, each named.");
  AddPieceArgument(d, design->piece);
  d->add_option("-o,--output", design->output, "NOMINAL.csv to write");
  d->add_option("--cmm", design->cmm, "also write DIR/program.txt: the point list as a CMM program");
  d->add_option("--gcode", design->gcode, "also write the tool path that cuts the features (ISO G-code)");
  d->add_option("--describe", design->describe, "also write the piece's description as JSON (edit it and give it back)");
  d->add_flag("--json", design->json, "print a summary as JSON: points, features, series");
  d->footer("Example:\n  fvm testpiece design -o nominal.csv --gcode piece.nc --cmm cmm --describe piece.json");
  d->callback([design] { RunPieceDesign(*design); });

  auto verify = std::make_shared<PieceVerifyCommand>();
  workflows::MachinedPieceVerifyOptions& o = verify->options;
  CLI::App* v = tp->add_subcommand("verify", "volumetric and geometric verification of a machine from its test piece's CMM measurement");
  AddDetails(v,
             "MEAS.csv id,x,y,z,xm,ym,zm: nominal (machine) and CMM-measured coordinates (mm). Identifies the 21 error "
             "functions (polynomials of --order in --basis on the piece's extent) and the piece's datum (its rigid "
             "transform into the CMM frame) as fvm verify does for a tracker, logs max / mean / min per iteration, and "
             "says per error whether the points (with --nominal: the series X1..Z3 alone) recover it.");
  v->add_option("DATA", o.machine.data, "CMM readings: id,x,y,z,xm,ym,zm (mm)")->required();
  v->add_option("--chain", o.machine.chain, "F-notation chain")->capture_default_str();
  v->add_option("--basis", o.machine.basis, "polynomial basis")->check(CLI::IsMember({"power", "legendre", "chebyshev"}))->capture_default_str();
  v->add_option("--order", o.order, "polynomial order of each error function")->check(Count(1, 3))->capture_default_str();
  AddToolOption(v, o.machine, "tool offset X,Y,Z in mm (tool length along Z); twice for two tools (a `tool` column)");
  AddTravelOption(v, o.machine, "domain of the error functions LXxLYxLZ[@X0,Y0,Z0] (default: the span of the points)");
  v->add_option("--validate", o.machine.validate, "other readings to judge the model on (never fitted)");
  AddMaxErrorOption(v, o.machine);
  v->add_option("--nominal", o.nominal, "NOMINAL.csv of the piece: its series column selects X1..Z3 for the geometric verification");
  v->add_option("--report", verify->report, "write an HTML report (iterations, histograms, error functions, geometric table)");
  v->add_flag("--json", verify->json, "print the result as JSON");
  v->footer("Example:\n  fvm simulate testpiece -o tp --validation 30,30,30\n"
            "  fvm testpiece verify tp/measured.csv --basis chebyshev --order 2 --nominal tp/nominal.csv --validate tp/validation.csv --json");
  v->callback([verify] { RunPieceVerify(*verify); });
}

void RegisterSimulateTestPiece(CLI::App* simulate) {
  auto command = std::make_shared<PieceSimulateCommand>();
  workflows::SimulateTestPieceOptions& o = command->options;
  CLI::App* sub = simulate->add_subcommand("testpiece", "a test piece cut by a machine with known errors and measured on a CMM, with the truth");
  AddDetails(sub,
             "Writes DIR/nominal.csv, DIR/measured.csv (id,x,y,z,xm,ym,zm: the CMM's readings of the piece at its datum, "
             "with normal noise), DIR/truth.json (the errors, datum, tool, noise) and with --validation a noise-free grid "
             "over the piece (validation.csv). Errors: [Lorente 2021] Table 4's test functions by default, --errors FILE.json "
             "(fvm simulate tracker's format), or a random machine that no polynomial represents (--mean-error-um).");
  AddPieceArgument(sub, o.piece);
  sub->add_option("-o,--output", command->output, "directory to write")->required();
  auto* errors = sub->add_option("--errors", o.errors, "machine truth JSON")->check(CLI::ExistingFile);
  sub->add_option("--mean-error-um", o.mean_error_um, "a random machine (cubics + sines) of this mean volumetric error over the piece")
      ->check(Within(1e-3, 1e4, "um"))
      ->excludes(errors);
  sub->add_option("--seed", o.seed, "random machine and CMM noise (same seed, same bytes)")->check(Within(kSeed))->capture_default_str();
  sub->add_option("--noise-um", o.noise_um, "CMM noise per coordinate (um)")->check(Within(0.0, 1e3, "um"))->capture_default_str();
  sub->add_option("--points", o.points, "all, pyramid ([Lorente 2021]'s 167-point test) or series (X1..Z3 only)")
      ->check(CLI::IsMember({"all", "pyramid", "series"}))
      ->capture_default_str();
  sub->add_option("--chain", o.chain, "F-notation chain")->check(Parses([](const std::string& t) { stage::AxisChain::Parse(t); }, "CHAIN"))->capture_default_str();
  sub->add_option_function<std::string>(
         "--tool", [&o](const std::string& t) { o.tool = ParseVector3(t, "--tool", "0,0,100"); }, "tool offset X,Y,Z (mm)")
      ->check(NumbersCheck(3, "--tool", "0,0,100"))
      ->default_str("0,0,100");
  sub->add_option_function<std::string>(
         "--datum", [&o](const std::string& t) { o.datum = ParsePose(t, "--datum"); },
         "the piece's pose on the CMM: X,Y,Z (mm), A,B,C (XYZ Euler, deg)")
      ->check(PoseCheck("--datum"))
      ->default_str("20,-15,5,0.05,-0.1,12");
  sub->add_flag("--json", command->json, "print what was written as JSON: output, points, errors, noise, seed, datum");
  sub->add_flag("--proposed-series", o.proposed_series,
                "also cut the series X1..Z3 with an oriented boring bar 30 mm off the spindle axis (at 0 and 180 deg) and "
                "a tool 50 mm longer: the series that recover ECZ, ECY, EAZ and EBZ");
  sub->add_option_function<std::string>(
         "--validation",
         [&o](const std::string& t) { o.validation_step = ParseVector3(t, "--validation", "30,30,30", kStepMm); },
         "also a noise-free grid with these steps SX,SY,SZ (mm) over the piece")
      ->check(NumbersCheck(3, "--validation", "30,30,30", kStepMm));
  sub->footer("Example:\n  fvm simulate testpiece -o tp --seed 1 --validation 30,30,30\n  fvm simulate testpiece -o pyr --points pyramid");
  sub->callback([command] { RunPieceSimulate(*command); });
}

}  // namespace fvm::cli
