// fvm: the command line that joins imaging, stage and artefacts. One file per subcommand.

#include <fmt/core.h>

#include <glog/logging.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <exception>
#include <memory>
#include <span>
#include <sstream>
#include <string>
#include <string_view>

#include "core/exit_codes.h"
#include "core/input_error.h"
#include "core/version.h"
#include "fvm/commands.h"
#include "fvm/option_ranges.h"

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
    throw CLI::RuntimeError(kExitUsage);
  });
}

namespace {

// The command list of `fvm --help` shows the first line of each description; a command's own --help shows it all
// (the summary, a blank line, then the paragraph).
class SummaryFormatter : public CLI::Formatter {
 public:
  std::string make_subcommand(const CLI::App* sub) const override {
    const std::string& description = sub->get_description();
    std::stringstream out;
    CLI::detail::format_help(out, sub->get_display_name(true), description.substr(0, description.find('\n')),
                             column_width_);
    return out.str();
  }
};

// "fvm tiles plan": the commands the parse reached before it failed, for the message and its --help hint.
std::string CommandPath(const CLI::App& app) {
  std::string path = "fvm";
  const CLI::App* at = &app;
  while (true) {
    const auto parsed = at->get_subcommands();
    if (parsed.empty()) break;
    at = parsed.front();
    path += " " + at->get_name();
  }
  return path;
}

// The commands, in the order `fvm --help` lists them.
struct Command {
  std::string_view name;
  void (*add)(CLI::App&);
};
constexpr Command kCommands[] = {
    {"calibrate", RegisterCalibrate}, {"correct", RegisterCorrect},   {"compare", RegisterCompare},
    {"diff", RegisterDiff},           {"diagnose", RegisterDiagnose}, {"simulate", RegisterSimulate},
    {"info", RegisterInfo},           {"fit", RegisterFit},           {"focus", RegisterFocus},
    {"tiles", RegisterTiles},         {"stitch", RegisterStitch},     {"verify", RegisterVerify},
    {"multilaterate", RegisterMultilaterate}, {"uncertainty", RegisterUncertainty},
    {"testpiece", RegisterTestPiece},
};

// Building every command's options (thousands of strings, names and checks) took more CPU than anything else in
// `fvm --version` (issue 47), so a run builds only the command it names: the first argument that is a command's
// name (the global options before it take numbers). Without one, all of them (`fvm --help` and a mistyped command
// see the whole list), or none for `fvm --version`; all for --list-numeric-options.
std::span<const Command> CommandsToRegister(int argc, char** argv) {
  const std::span<const Command> all(kCommands);
  const auto given = [&](std::string_view option) {
    return std::any_of(argv + 1, argv + argc, [&](const char* arg) { return option == arg; });
  };
  if (given("--list-numeric-options")) return all;
  for (int i = 1; i < argc; ++i) {
    for (const Command& command : all) {
      if (command.name == argv[i]) return all.subspan(static_cast<size_t>(&command - kCommands), 1);
    }
  }
  if (given("--version") && !given("-h") && !given("--help") && !given("--help-all")) return {};
  return all;
}

constexpr const char* kExitCodeFooter =
    "Options --threads N and --quiet apply to every command and may follow it.\n"
    "Run 'fvm <command> --help' for the options of a command.\n"
    "\n"
    "Example (the sample batch: calibrate the stage, then correct a held-out export with it):\n"
    "  fvm calibrate samples/bar17 --model 27 -o stage.json\n"
    "  fvm correct --calibration stage.json samples/bar17/val-01.free.csv -o val-01.corrected.csv\n"
    "\n"
    "Exit codes:\n"
    "  0  done\n"
    "  1  bad input: a file, value or combination to fix (the message names it)\n"
    "  2  usage: unknown command or option, missing argument, or a command not built yet\n"
    "  3  did not converge: the outputs were written but must not be trusted as they are";

}  // namespace
}  // namespace fvm::cli

int main(int argc, char** argv) {
  // Ceres reports through glog: its warnings (and, before InitGoogleLogging, a notice that logging is not set up)
  // would reach stderr in a clean run. fvm says what matters itself; only a fatal check, which aborts, is logged.
  FLAGS_minloglevel = google::GLOG_FATAL;
  FLAGS_stderrthreshold = google::GLOG_FATAL;
  FLAGS_logtostderr = false;
  google::InitGoogleLogging("fvm");
  // Named here, not from argv[0]: messages and usage lines say "fvm", never the binary's full path.
  CLI::App app{"fvm: calibrate the motion stage of focus-variation microscopes (and machine tools measured with "
               "laser\ntrackers) from measurements of an uncalibrated artefact. Units: mm and rad in files, um and "
               "urad in reports.",
               "fvm"};
  app.formatter(std::make_shared<fvm::cli::SummaryFormatter>());
  app.set_version_flag("--version", fmt::format("fvm {} (commit {})", fvm::Version(), fvm::GitCommit()));
  app.require_subcommand(1);
  // Global options may follow the command (fvm stitch ... --threads 2): subcommands inherit this.
  app.fallthrough();
  app.footer(fvm::cli::kExitCodeFooter);
  fvm::cli::CommonOptions& common = fvm::cli::Common();
  app.add_option("--threads", common.threads,
                 "threads for identification, registration, mosaics and focus stacks (default: all cores)")
      ->check(fvm::cli::Count(0, 1024));
  app.add_flag("-q,--quiet", common.quiet, "no progress lines on stderr (they appear only on a terminal anyway)");

  for (const fvm::cli::Command& command : fvm::cli::CommandsToRegister(argc, argv)) command.add(app);
  // Every numeric option, whatever command declared it, refuses nan and inf; --list-numeric-options (hidden)
  // prints each with its span for the test that tries them all (tests/fvm/numeric_options_cli_test.cmake).
  fvm::cli::RefuseNonFinite(app);
  app.add_flag_callback(
         "--list-numeric-options",
         [&app] {
           fmt::print("{}", fvm::cli::NumericOptionList(app));
           throw CLI::Success();
         },
         "print every numeric option: COMMAND, FLAG, FORM, MIN, MAX, whole|real (tab-separated)")
      ->group("");

  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // a command that already said why (not built yet)
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --help-all, --version
    const std::string command = fvm::cli::CommandPath(app);
    // A hidden option (an old spelling) has an empty name in CLI11's message, ": why"; its checks name it.
    std::string why = e.what();
    if (why.starts_with(": ")) why.erase(0, 2);
    fmt::print(stderr, "{}: {}\nRun '{} --help' for its options.\n", command, why, command);
    return fvm::kExitUsage;
  } catch (const fvm::InputError& e) {
    fmt::print(stderr, "fvm: error: {}\n", e.what());
    return fvm::kExitBadInput;
  } catch (const fvm::NotConvergedError& e) {
    fmt::print(stderr, "fvm: did not converge: {}\n", e.what());
    return fvm::kExitNotConverged;
  } catch (const std::exception& e) {
    // Library checks (std::invalid_argument) are bad input reaching a deeper layer; they read the same way.
    fmt::print(stderr, "fvm: error: {}\n", e.what());
    return fvm::kExitBadInput;
  }
  return fvm::kExitOk;
}
