// fvm verify DATA.csv --chain XFYZ --order N --tool X,Y,Z [--fit-pose | --pose ...] -o MACHINE.json: volumetric
// verification of a machine tool from laser-tracker readings (workflows/verify_machine.h).

#include <fmt/core.h>

#include "core/exit_codes.h"
#include "core/file_io.h"
#include "fvm/summary_output.h"
#include "fvm/commands.h"
#include "fvm/machine_options.h"
#include "workflows/verify_summary.h"

namespace fvm::cli {
namespace {

struct VerifyCommand {
  workflows::VerifyMachineOptions options;
  std::string output, report;
  bool json = false;
};

void Run(VerifyCommand command) {
  workflows::VerifyMachineOptions& options = command.options;
  options.machine.threads = ThreadCount();
  options.Check();
  const workflows::MachineProblem problem = workflows::LoadMachineProblem(options.machine);
  const workflows::MachineVerification verified = workflows::VerifyMachine(problem, options);
  workflows::Summary summary = workflows::Summarize(problem, options, verified, command.output);
  AddSortedPath(summary.json, "data", options.machine.data);
  if (!command.report.empty()) report::Write(command.report, *summary.report);
  if (!command.output.empty()) {
    nlohmann::json model = workflows::MachineModelJson(problem, options, verified);
    model["verification"]["data"] = options.machine.data;
    WriteFileAtomically(command.output, model.dump(2) + "\n");
  }
  fmt::print("{}", command.json ? summary.json.dump(2) + "\n" : summary.text);
  const stage::IdentificationResult& r = verified.Chosen().result.identified;
  if (!r.converged) throw NotConvergedError(workflows::NotConvergedReason(r));
}

}  // namespace

void RegisterVerify(CLI::App& app) {
  auto command = std::make_shared<VerifyCommand>();
  CLI::App* sub = app.add_subcommand("verify", "machine-tool volumetric verification from laser-tracker readings");
  AddDetails(sub,
             "Identifies the 21 geometric error functions of a three-axis machine (polynomials of --order in --basis) "
             "and the tracker pose from readings at commanded points, each weighted by the tracker's noise model "
             "(a 3x3 covariance per point), or by its own covariance where the readings carry one (cxx..czz, as "
             "fvm multilaterate --verify-readings writes). Volumetric error: distance between a reading and the model's prediction "
             "of the ideal machine (initial) or of the identified one (final), in the tracker frame. Error functions "
             "only matter up to their value at each axis' origin, which the tracker pose absorbs: the pose is "
             "estimated jointly unless --pose holds it, and terms the data cannot separate are fixed and named.");
  AddMachineOptions(sub, command->options.machine);
  sub->add_option_function<std::string>(
         "--order", [command](const std::string& text) { command->options.orders = workflows::ParseOrders(text); },
         "polynomial order of each error function, 1-3, or auto (held-out points or BIC)")
      ->check(CLI::IsMember({"1", "2", "3", "auto"}))
      ->default_str("3");
  sub->add_option("-o,--output", command->output, "write the identified machine (calibration JSON with the tracker pose)");
  sub->add_option("--report", command->report,
                  "write an HTML report with SVG plots to this directory (error functions with 95 % bands, tracker "
                  "pose, fixed terms, volumetric errors and their map)");
  sub->add_flag("--json", command->json, "print the result as JSON");
  sub->footer(
      "Example:\n  fvm simulate tracker --seed 1 --validation mesh:250,250,200 -o plan\n"
      "  fvm verify plan/readings.csv --chain XFYZ --order 3 --tool 0,0,100 --validate plan/validation.csv -o machine.json \\\n"
      "    --report machine-report");
  sub->callback([command] { Run(*command); });
}

}  // namespace fvm::cli
