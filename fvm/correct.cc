// fvm correct --calibration CAL.json IN -o OUT: compensate a stitching-free export.

#include <fmt/core.h>

#include <cmath>

#include "core/file_io.h"
#include "artefacts/io/centre_export.h"
#include "core/input_error.h"
#include "stage/io/calibration_file.h"
#include "fvm/commands.h"

namespace fvm::cli {
namespace {

struct CorrectArgs {
  std::string calibration;
  std::string input;
  std::string output;
  bool json = false;
};

void Run(const CorrectArgs& args) {
  const std::filesystem::path in(args.input);
  if (in.extension() != ".csv") {
    throw InputError(fmt::format("{}: only centre exports (.csv) can be corrected so far; point clouds and height "
                                 "maps wait for the imaging readers (issue 4)", args.input));
  }
  const stage::Calibration cal = stage::ReadCalibration(args.calibration);
  const artefacts::CentreExport input = artefacts::ReadCentreExport(in);

  // Same rows, compensated; u_x, u_y, u_z are the standard uncertainties the model's covariance gives each point.
  std::string csv = fmt::format("# corrected by fvm {} with {} (model {})\n", FVM_VERSION, args.calibration, cal.model);
  for (const std::string& c : input.comments) csv += "#" + c + "\n";
  csv += "id,x,y,z,u_x,u_y,u_z";
  const bool has_t = !input.centres.empty() && input.centres.front().t_s.has_value();
  if (has_t) csv += ",t";
  csv += "\n";
  nlohmann::json doc;
  double largest_shift = 0.0;
  for (const artefacts::CentreRecord& r : input.centres) {
    const stage::CorrectedPoint p = stage::Correct(cal, r.position);
    const Eigen::Vector3d u = p.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    csv += fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f}", r.id, p.position.x(), p.position.y(), p.position.z(),
                       u.x(), u.y(), u.z());
    if (has_t) csv += fmt::format(",{:.3f}", r.t_s.value_or(NAN));
    csv += "\n";
    largest_shift = std::max(largest_shift, (p.position - r.position).norm());
    doc["centres"].push_back({{"id", r.id}, {"x", p.position.x()}, {"y", p.position.y()}, {"z", p.position.z()},
                              {"u_um", {u.x() * 1e3, u.y() * 1e3, u.z() * 1e3}},
                              {"shift_um", (p.position - r.position).norm() * 1e3}});
  }
  WriteFileAtomically(args.output, csv);
  if (args.json) {
    doc["output"] = args.output;
    fmt::print("{}\n", doc.dump(2));
    return;
  }
  fmt::print("corrected {} centres of {} with model {}; largest shift {:.1f} um; written to {}\n", input.centres.size(),
             args.input, cal.model, largest_shift * 1e3, args.output);
}

}  // namespace

void RegisterCorrect(CLI::App& app) {
  auto args = std::make_shared<CorrectArgs>();
  CLI::App* sub = app.add_subcommand("correct", "compensate a stitching-free export with a calibration");
  sub->add_option("--calibration", args->calibration, "calibration file written by 'fvm calibrate -o'")->required();
  sub->add_option("IN", args->input, "stitching-free centre export (CSV: id,x,y,z in mm)")->required();
  sub->add_option("-o,--output", args->output, "corrected export (CSV: id,x,y,z,u_x,u_y,u_z in mm)")->required();
  sub->add_flag("--json", args->json, "print the corrected centres as JSON");
  sub->footer("Example:\n  fvm calibrate samples/bar17 --model 27 -o stage.json && fvm correct --calibration stage.json "
              "samples/bar17/val-01.free.csv -o val-01.corrected.csv");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
