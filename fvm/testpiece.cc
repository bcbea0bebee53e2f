// fvm testpiece design|verify and fvm simulate testpiece: the machined test piece of [Lorente 2021]. The verification
// is fvm verify's (fvm/machine_problem.h): a CMM-measured piece is a tracker whose pose is the piece's datum.

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "artefacts/geometry/machined_piece.h"
#include "artefacts/io/machine_truth_file.h"
#include "artefacts/io/tracker_readings.h"
#include "artefacts/simulation/machine_tool_simulation.h"
#include "artefacts/simulation/machined_piece_simulation.h"
#include "core/exit_codes.h"
#include "core/file_io.h"
#include "core/input_error.h"
#include "fvm/commands.h"
#include "fvm/machine_problem.h"
#include "report/machine_report.h"
#include "fvm/option_parsing.h"
#include "stage/io/calibration_file.h"
#include "stage/series_extraction.h"
#include "stage/machined_piece_verification.h"
#include "workflows/machined_piece_verify.h"

namespace fvm::cli {
namespace {

artefacts::MachinedPieceDescription PieceOf(const std::string& path) {
  return path.empty() ? artefacts::PublishedMachinedPiece() : artefacts::ReadMachinedPiece(path);
}

// PIECE, the optional description both design and simulate take.
void AddPieceArgument(CLI::App* sub, std::string& piece) {
  sub->add_option("PIECE", piece, "piece description (JSON); default: the published piece of [Lorente 2021]")->check(CLI::ExistingFile);
}

using workflows::IsSeries;

// ---------------------------------------------------------------------------------------------- design

struct DesignArgs {
  std::string piece, output, cmm, gcode, describe;
  bool json = false;
};

void RunDesign(const DesignArgs& args) {
  const artefacts::MachinedPieceDescription piece = PieceOf(args.piece);
  const std::vector<artefacts::PiecePoint> points = artefacts::NominalPoints(piece);
  if (points.empty()) throw InputError(fmt::format("{}: the piece has no probe points; give each feature \"points\"", args.piece));
  if (!args.output.empty()) artefacts::WriteNominalPoints(args.output, points);
  if (!args.cmm.empty()) {
    std::filesystem::create_directories(args.cmm);
    WriteFileAtomically(std::filesystem::path(args.cmm) / "program.txt", artefacts::CmmProgram(points));
  }
  if (!args.gcode.empty()) WriteFileAtomically(args.gcode, artefacts::CuttingProgram(piece));
  if (!args.describe.empty()) WriteFileAtomically(args.describe, artefacts::MachinedPieceJson(piece));
  std::map<std::string, int> per_series, per_kind;
  for (const artefacts::PiecePoint& p : points) {
    if (IsSeries(p.series)) ++per_series[p.series];
    ++per_kind[std::string(artefacts::FeatureKindName(p.kind))];
  }
  if (args.json) {
    nlohmann::json j{{"points", points.size()}, {"features", piece.features.size()},
                     {"envelope_mm", {piece.envelope.x(), piece.envelope.y(), piece.envelope.z()}},
                     {"series", per_series}, {"points_by_kind", per_kind}};
    fmt::print("{}\n", j.dump(2));
    return;
  }
  fmt::print("test piece {:.0f} x {:.0f} x {:.0f} mm: {} features, {} probe points{}\n", piece.envelope.x(), piece.envelope.y(),
             piece.envelope.z(), piece.features.size(), points.size(), args.output.empty() ? "" : " -> " + args.output);
  for (const auto& [kind, n] : per_kind) fmt::print("  {:<13} {:4d} points\n", kind, n);
  std::string series;
  for (const auto& [name, n] : per_series) series += fmt::format(" {}:{}", name, n);
  fmt::print("  series{}\n", series);
}

// ---------------------------------------------------------------------------------------------- verify

struct MachinedPieceVerifyArgs : MachineArgs {
  int order = 2;
  std::string nominal, report;
  bool json = false;
};

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

// Counts of the volumetric errors before and after in bins of `width` um: the report's histograms ([Lorente 2021] Figs.
// 126-127, 132-133).
report::MachineReportData::Table Histogram(const std::vector<report::MachineReportData::PointError>& points) {
  double top = 0;
  for (const auto& p : points) top = std::max({top, p.before_um, p.after_um});
  const double width = std::max(0.5, std::ceil(top / 12.0 * 2.0) / 2.0);
  const int bins = std::max(1, static_cast<int>(std::ceil(top / width + 1e-12)));
  std::vector<int> before(static_cast<size_t>(bins)), after(static_cast<size_t>(bins));
  for (const auto& p : points) {
    ++before[static_cast<size_t>(std::min(bins - 1, static_cast<int>(p.before_um / width)))];
    ++after[static_cast<size_t>(std::min(bins - 1, static_cast<int>(p.after_um / width)))];
  }
  report::MachineReportData::Table t{"Histogram of the volumetric errors", "Number of points per error bin, before and after the verification.",
                             {"error (um)", "before", "after", ""}, {}};
  const int most = std::max(*std::max_element(before.begin(), before.end()), *std::max_element(after.begin(), after.end()));
  for (int b = 0; b < bins; ++b) {
    const size_t i = static_cast<size_t>(b);
    t.rows.push_back({fmt::format("{:.1f} - {:.1f}", b * width, (b + 1) * width), std::to_string(before[i]), std::to_string(after[i]),
                      std::string(static_cast<size_t>(40 * before[i] / std::max(1, most)), '#') + " | " +
                          std::string(static_cast<size_t>(40 * after[i] / std::max(1, most)), '*')});
  }
  return t;
}

void RunVerify(const MachinedPieceVerifyArgs& args) {
  const MachineProblem problem = LoadMachineProblem(args);
  const workflows::MachinedPieceVerifyResult verified = workflows::VerifyMachinedPiece(problem, {args.order, args.nominal});
  const stage::MachinedPieceVerification& v = verified.verification;
  const stage::IdentificationResult& r = v.result.identified;
  const std::vector<stage::TermRecovery>& geometric = verified.geometric;
  const std::string& geometric_from = verified.geometric_from;

  nlohmann::json doc;
  doc["data"] = args.data;
  doc["chain"] = problem.chain.code;
  doc["basis"] = args.basis;
  doc["order"] = args.order;
  doc["points"] = problem.readings.points.size();
  doc["weights"] = "equal (CMM)";
  doc["initial"] = ErrorJson(v.result.initial);
  doc["final"] = ErrorJson(v.result.final);
  doc["final"]["rms_um"] = r.residual_summary.rms_um();
  if (verified.validation) {
    doc["validation"] = {{"points", problem.validation->points.size()}, {"initial", ErrorJson(verified.validation->before)},
                         {"final", ErrorJson(verified.validation->after)}};
  }
  doc["iterations"] = nlohmann::json::array();
  for (const stage::ResidualSummary& e : v.iterations) doc["iterations"].push_back(ErrorJson(e));
  if (verified.extraction) {
    doc["extraction"] = nlohmann::json::array();
    for (const stage::ExtractedError& e : *verified.extraction) {
      const bool angle = e.error[1] == 'A' || e.error[1] == 'B' || e.error[1] == 'C';
      nlohmann::json values = nlohmann::json::array();
      for (double x : e.value) values.push_back(x * (angle ? 1e6 : 1e3));
      doc["extraction"].push_back({{"error", e.error}, {"coordinate_mm", e.coordinate}, {"value_um_or_urad", values}});
    }
  }
  doc["geometric"] = TermsJson(geometric);
  doc["geometric_from"] = geometric_from;
  const nlohmann::json calibration = stage::CalibrationToJson(r);
  doc["fixed"] = calibration["fixed"];
  doc["parameters"] = calibration["parameters"];
  doc["pose"] = PoseJson(r.pose, &r.pose_covariance);
  doc["pose"]["estimated"] = args.pose.empty();
  doc["pose"]["initial"] = PoseJson(v.result.initial_pose, nullptr);
  doc["datum_absorbs"] = nlohmann::json::array();
  for (const stage::FixedCoefficient& f : v.datum_absorbs) doc["datum_absorbs"].push_back({{"name", f.name}, {"reason", f.reason}});
  doc["plausibility"] = PlausibilityJson(r, args.max_error_mm);
  doc["converged"] = r.converged;
  if (!r.converged) doc["solver_report"] = r.solver_report;

  if (!args.report.empty()) {
    report::MachineReportData data = MachineVerificationReport(args, doc, v.result, problem.observations,
                                                       problem.validation ? &problem.validation_observations : nullptr,
                                                       problem.options.tool_offsets);
    data.title = fmt::format("fvm testpiece verify: {} {} order {} on {}", problem.chain.code, args.basis, args.order, args.data);
    for (report::MachineReportData::Table& t : data.tables) {
      if (t.heading == "Tracker pose") t.heading = "Datum: the piece in the CMM frame";
    }
    report::MachineReportData::Table log{"Iterations", "Volumetric error after each solver iteration (0: the ideal machine at the initial datum).",
                                 {"iteration", "max (um)", "mean (um)", "min (um)"}, {}};
    for (size_t i = 0; i < v.iterations.size(); ++i) {
      const stage::ResidualSummary& e = v.iterations[i];
      log.rows.push_back({std::to_string(i), fmt::format("{:.2f}", e.max_um()), fmt::format("{:.2f}", e.mean_um()), fmt::format("{:.2f}", e.min_um())});
    }
    data.tables.insert(data.tables.begin(), log);
    data.tables.insert(data.tables.begin() + 1, Histogram(data.readings));
    report::MachineReportData::Table g{"Geometric verification", "From " + geometric_from + ": each error at the far end of its axis.",
                               {"error", "recoverable", "value (um or urad)", "u", "why not"}, {}};
    for (const stage::TermRecovery& t : geometric) {
      g.rows.push_back({t.error, t.recoverable ? "yes" : t.partly ? "partly" : "no", fmt::format("{:.2f}", t.value), fmt::format("{:.2f}", t.u), t.reason});
    }
    data.tables.push_back(g);
    report::WriteMachineReport(args.report, data);
  }
  if (args.json) {
    fmt::print("{}\n", doc.dump(2));
  } else {
    fmt::print("verified the test piece: {} points, {} {} order {}\n", problem.readings.points.size(), problem.chain.code, args.basis, args.order);
    fmt::print("  iteration      max     mean      min (um)\n");
    for (size_t i = 0; i < v.iterations.size(); ++i) {
      fmt::print("  {:9d} {:8.2f} {:8.2f} {:8.2f}\n", i, v.iterations[i].max_um(), v.iterations[i].mean_um(), v.iterations[i].min_um());
    }
    if (problem.validation) {
      fmt::print("  validation ({} points): mean {:.2f} -> {:.2f} um, max {:.2f} -> {:.2f} um\n", problem.validation->points.size(),
                 verified.validation->before.mean_um(), verified.validation->after.mean_um(), verified.validation->before.max_um(),
                 verified.validation->after.max_um());
    }
    std::string lost;
    for (const stage::TermRecovery& t : geometric) {
      if (!t.recoverable) lost += " " + t.error + (t.partly ? "(partly)" : "");
    }
    fmt::print("  geometric ({}): not recovered:{}\n", geometric_from, lost.empty() ? " none" : lost);
    fmt::print("  datum: {:.4f}, {:.4f}, {:.4f} mm; absorbs {} coefficient(s) (see --json datum_absorbs)\n", r.pose.translation.x(),
               r.pose.translation.y(), r.pose.translation.z(), v.datum_absorbs.size());
  }
  if (!r.converged) throw NotConvergedError(NotConvergedReason(r));
}

// ---------------------------------------------------------------------------------------------- simulate

struct SimulateArgs {
  std::string piece, output, errors, only = "all", tool = "0,0,100", datum = "20,-15,5,0.05,-0.1,12", validation;
  std::uint64_t seed = 1;
  double noise_um = 1.0, mean_error_um = 0.0;
  std::string chain = "XFYZ";
  bool proposed = false;
  bool json = false;
};

// The series cut again with the tools that make the Z and Y yaws and the Z rotations observable: a boring bar whose
// edge sits 30 mm off the spindle axis, spindle oriented (M19) at 0 and 180 deg, and a tool 50 mm longer.
std::vector<Eigen::Vector3d> ProposedTools(const Eigen::Vector3d& tool) {
  return {tool + Eigen::Vector3d(30, 0, 0), tool - Eigen::Vector3d(30, 0, 0), tool + Eigen::Vector3d(0, 0, 50)};
}

void RunSimulate(const SimulateArgs& args) {
  const artefacts::MachinedPieceDescription piece = PieceOf(args.piece);
  std::vector<artefacts::PiecePoint> points = artefacts::NominalPoints(piece);
  if (args.only != "all") {
    std::erase_if(points, [&](const artefacts::PiecePoint& p) {
      return args.only == "pyramid" ? p.kind != artefacts::FeatureKind::kPyramid : !IsSeries(p.series);
    });
  }
  stage::AxisChain chain = stage::AxisChain::Parse(args.chain);
  chain.tool_offset = ParseVector3(args.tool, "--tool", "0,0,100");
  const artefacts::Workspace ws = artefacts::PieceWorkspace(piece);
  const artefacts::MachineTruth truth = !args.errors.empty()       ? artefacts::ReadMachineTruth(args.errors, ws)
                                        : args.mean_error_um > 0.0 ? artefacts::RandomMachineTruth(chain, ws, args.seed, args.mean_error_um)
                                                                   : artefacts::PublishedTestFunctions(ws);
  artefacts::CmmSimulation cmm;
  cmm.datum = ParsePose(args.datum, "--datum");
  cmm.sigma_mm = args.noise_um * 1e-3;
  cmm.seed = args.seed;
  artefacts::TrackerReadings measured = artefacts::SimulateMachinedPiece(chain, truth, points, cmm);
  std::vector<artefacts::PiecePoint> nominal = points;
  if (args.proposed) {
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
        measured.points.push_back(r);
      }
      nominal.insert(nominal.end(), again.begin(), again.end());
    }
  }
  measured.comments = {fmt::format("fvm simulate testpiece: {} points, CMM noise {} um, seed {}", points.size(), args.noise_um, args.seed)};
  std::filesystem::create_directories(args.output);
  const std::filesystem::path dir(args.output);
  artefacts::WriteNominalPoints((dir / "nominal.csv").string(), nominal);
  artefacts::WriteTrackerReadings(dir / "measured.csv", measured);
  if (!args.validation.empty()) {
    // A noise-free grid over the whole piece (not only where features are): how well the identified machine
    // predicts the piece everywhere.
    const Eigen::Vector3d step = ParseVector3(args.validation, "--validation", "30,30,30", kStepMm);
    std::vector<artefacts::PiecePoint> grid;
    for (const artefacts::PlannedPoint& p : artefacts::PlanMesh(ws, step)) grid.push_back({"G" + p.id.substr(1), p.nominal, "", "", {}});
    artefacts::CmmSimulation exact = cmm;
    exact.sigma_mm = 0.0;
    artefacts::TrackerReadings g = artefacts::SimulateMachinedPiece(chain, truth, grid, exact);
    g.comments = {"fvm simulate testpiece: noise-free validation grid over the piece"};
    artefacts::WriteTrackerReadings(dir / "validation.csv", g);
  }
  nlohmann::json t = nlohmann::json::parse(artefacts::MachineTruthJson(truth));
  t["chain"] = chain.code;
  t["tool_mm"] = {chain.tool_offset.x(), chain.tool_offset.y(), chain.tool_offset.z()};
  t["datum"] = PoseJson(cmm.datum, nullptr);
  t["cmm_noise_um"] = args.noise_um;
  t["seed"] = args.seed;
  t["errors"] = !args.errors.empty() ? args.errors : args.mean_error_um > 0 ? std::string("random") : std::string("[Lorente 2021] Table 4");
  WriteFileAtomically(dir / "truth.json", t.dump(2) + "\n");
  if (args.json) {
    nlohmann::json j{{"output", args.output}, {"points", measured.points.size()}, {"errors", t["errors"]},
                     {"cmm_noise_um", args.noise_um}, {"seed", args.seed}, {"datum", t["datum"]}};
    fmt::print("{}\n", j.dump(2));
    return;
  }
  fmt::print("simulated the test piece into {}: {} points ({}), errors {}, CMM noise {} um, seed {}\n", args.output, measured.points.size(),
             args.only, t["errors"].get<std::string>(), args.noise_um, args.seed);
  if (args.proposed) {
    std::string tools = fmt::format("--tool {},{},{}", chain.tool_offset.x(), chain.tool_offset.y(), chain.tool_offset.z());
    for (const Eigen::Vector3d& t : ProposedTools(chain.tool_offset)) tools += fmt::format(" --tool {},{},{}", t.x(), t.y(), t.z());
    fmt::print("  the series cut again with three more tools (the `tool` column): verify with {}\n", tools);
  }
}

}  // namespace

void RegisterTestPiece(CLI::App& app) {
  CLI::App* tp = app.add_subcommand("testpiece", "the machined test piece of [Lorente 2021]: design it, verify a machine from its CMM measurement");
  tp->require_subcommand(1);
  tp->footer("Examples:\n  fvm testpiece design -o nominal.csv --gcode piece.nc --cmm cmm\n"
             "  fvm simulate testpiece -o tp && fvm testpiece verify tp/measured.csv --basis chebyshev --order 2");

  auto design = std::make_shared<DesignArgs>();
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
  d->callback([design] { RunDesign(*design); });

  auto verify = std::make_shared<MachinedPieceVerifyArgs>();
  verify->basis = "chebyshev";
  verify->tools = {"0,0,100"};
  verify->tracker = "none";
  verify->unweighted = true;
  CLI::App* v = tp->add_subcommand("verify", "volumetric and geometric verification of a machine from its test piece's CMM measurement");
  AddDetails(v,
             "MEAS.csv id,x,y,z,xm,ym,zm: nominal (machine) and CMM-measured coordinates (mm). Identifies the 21 error "
             "functions (polynomials of --order in --basis on the piece's extent) and the piece's datum (its rigid "
             "transform into the CMM frame) as fvm verify does for a tracker, logs max / mean / min per iteration, and "
             "says per error whether the points (with --nominal: the series X1..Z3 alone) recover it.");
  v->add_option("DATA", verify->data, "CMM readings: id,x,y,z,xm,ym,zm (mm)")->required();
  v->add_option("--chain", verify->chain, "F-notation chain")->capture_default_str();
  v->add_option("--basis", verify->basis, "polynomial basis")->check(CLI::IsMember({"power", "legendre", "chebyshev"}))->capture_default_str();
  v->add_option("--order", verify->order, "polynomial order of each error function")->check(Count(1, 3))->capture_default_str();
  v->add_option("--tool", verify->tools, "tool offset X,Y,Z in mm (tool length along Z); twice for two tools (a `tool` column)")
      ->check(NumbersCheck(3, "--tool", "0,0,100"))
      ->capture_default_str();
  v->add_option("--machine", verify->machine, "domain of the error functions LXxLYxLZ[@X0,Y0,Z0] (default: the span of the points)")
      ->check(MachineCheck());
  v->add_option("--validate", verify->validate, "other readings to judge the model on (never fitted)");
  AddMaxErrorOption(v, *verify);
  v->add_option("--nominal", verify->nominal, "NOMINAL.csv of the piece: its series column selects X1..Z3 for the geometric verification");
  v->add_option("--report", verify->report, "write an HTML report (iterations, histograms, error functions, geometric table)");
  v->add_flag("--json", verify->json, "print the result as JSON");
  v->footer("Example:\n  fvm simulate testpiece -o tp --validation 30,30,30\n"
            "  fvm testpiece verify tp/measured.csv --basis chebyshev --order 2 --nominal tp/nominal.csv --validate tp/validation.csv --json");
  v->callback([verify] { RunVerify(*verify); });
}

void RegisterSimulateTestPiece(CLI::App* simulate) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* sub = simulate->add_subcommand("testpiece", "a test piece cut by a machine with known errors and measured on a CMM, with the truth");
  AddDetails(sub,
             "Writes DIR/nominal.csv, DIR/measured.csv (id,x,y,z,xm,ym,zm: the CMM's readings of the piece at its datum, "
             "with normal noise), DIR/truth.json (the errors, datum, tool, noise) and with --validation a noise-free grid "
             "over the piece (validation.csv). Errors: [Lorente 2021] Table 4's test functions by default, --errors FILE.json "
             "(fvm simulate tracker's format), or a random machine that no polynomial represents (--mean-error-um).");
  AddPieceArgument(sub, args->piece);
  sub->add_option("-o,--output", args->output, "directory to write")->required();
  auto* errors = sub->add_option("--errors", args->errors, "machine truth JSON")->check(CLI::ExistingFile);
  sub->add_option("--mean-error-um", args->mean_error_um, "a random machine (cubics + sines) of this mean volumetric error over the piece")
      ->check(Within(1e-3, 1e4, "um"))
      ->excludes(errors);
  sub->add_option("--seed", args->seed, "random machine and CMM noise (same seed, same bytes)")->check(Within(kSeed))->capture_default_str();
  sub->add_option("--noise-um", args->noise_um, "CMM noise per coordinate (um)")->check(Within(0.0, 1e3, "um"))->capture_default_str();
  sub->add_option("--points", args->only, "all, pyramid ([Lorente 2021]'s 167-point test) or series (X1..Z3 only)")
      ->check(CLI::IsMember({"all", "pyramid", "series"}))
      ->capture_default_str();
  sub->add_option("--chain", args->chain, "F-notation chain")->check(Parses([](const std::string& t) { stage::AxisChain::Parse(t); }, "CHAIN"))->capture_default_str();
  sub->add_option("--tool", args->tool, "tool offset X,Y,Z (mm)")->check(NumbersCheck(3, "--tool", "0,0,100"))->capture_default_str();
  sub->add_option("--datum", args->datum, "the piece's pose on the CMM: X,Y,Z (mm), A,B,C (XYZ Euler, deg)")
      ->check(PoseCheck("--datum"))
      ->capture_default_str();
  sub->add_flag("--json", args->json, "print what was written as JSON: output, points, errors, noise, seed, datum");
  sub->add_flag("--proposed-series", args->proposed,
                "also cut the series X1..Z3 with an oriented boring bar 30 mm off the spindle axis (at 0 and 180 deg) and "
                "a tool 50 mm longer: the series that recover ECZ, ECY, EAZ and EBZ");
  sub->add_option("--validation", args->validation, "also a noise-free grid with these steps SX,SY,SZ (mm) over the piece")
      ->check(NumbersCheck(3, "--validation", "30,30,30", kStepMm));
  sub->footer("Example:\n  fvm simulate testpiece -o tp --seed 1 --validation 30,30,30\n  fvm simulate testpiece -o pyr --points pyramid");
  sub->callback([args] { RunSimulate(*args); });
}

}  // namespace fvm::cli
