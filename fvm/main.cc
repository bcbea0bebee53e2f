// fvm: the command line that joins imaging, stage and artefacts. One file per subcommand.

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <exception>

#include "fvm/commands.h"

namespace fvm::cli {

void AddNotBuilt(CLI::App& app, const std::string& name, const std::string& summary, int issue) {
  CLI::App* sub = app.add_subcommand(name, summary + "  [not built yet]");
  sub->allow_extras();
  sub->callback([name, issue] {
    if (issue > 0) {
      fmt::print(stderr, "fvm {}: not built yet (tracked in issue {}); nothing was done.\n", name, issue);
    } else {
      fmt::print(stderr, "fvm {}: not built yet (no issue filed for it yet); nothing was done.\n", name);
    }
    throw CLI::RuntimeError(2);
  });
}

}  // namespace fvm::cli

int main(int argc, char** argv) {
  using fvm::cli::AddNotBuilt;
  CLI::App app{
      "fvm: calibrate the motion stage of focus-variation microscopes (and machine tools measured with laser\n"
      "trackers) from measurements of an uncalibrated artefact. Units: mm and rad in files, um and urad in reports."};
  app.set_version_flag("--version", std::string("fvm ") + FVM_VERSION);
  app.require_subcommand(1);
  app.footer("Run 'fvm <command> --help' for the options of a command.");

  fvm::cli::RegisterCalibrate(app);
  fvm::cli::RegisterCorrect(app);
  fvm::cli::RegisterCompare(app);
  fvm::cli::RegisterDiff(app);
  fvm::cli::RegisterDiagnose(app);
  fvm::cli::RegisterSimulate(app);
  fvm::cli::RegisterInfo(app);
  fvm::cli::RegisterFit(app);
  fvm::cli::RegisterFocus(app);
  fvm::cli::RegisterTiles(app);
  fvm::cli::RegisterStitch(app);
  AddNotBuilt(app, "verify", "machine-tool volumetric verification with a laser tracker", 0);
  AddNotBuilt(app, "uncertainty", "Monte Carlo uncertainty of a verification or calibration", 0);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    fmt::print(stderr, "fvm: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
