#pragma once
// Every subcommand registers itself on the application from its own file (fvm/<command>.cc).

#include <CLI/CLI.hpp>
#include <string>

#include "fvm/option_ranges.h"

namespace fvm::cli {

// Options of the whole program (fvm --threads N --quiet), read by the commands that do long work.
struct CommonOptions {
  int threads = 0;     // 0: all cores
  bool quiet = false;  // no progress lines
};
CommonOptions& Common();
// Progress lines only where someone watches: stderr is a terminal and --quiet was not given.
bool ShowProgress();
// --threads for libraries that take a count: all cores when not given.
int ThreadCount();

// A command's own --help shows its one-line summary, a blank line, then these details; `fvm --help` lists only
// the summary.
inline void AddDetails(CLI::App* sub, const std::string& details) {
  sub->description(sub->get_description() + "\n\n" + details);
}

// An old spelling of `new_name` that scripts may still use: it sets the same variable, takes the same checks (its
// span) and is left out of --help.
template <typename T>
CLI::Option* AddHiddenAlias(CLI::App* app, const std::string& old_name, T& variable, const std::string& new_name) {
  CLI::Option* alias = app->add_option(old_name, variable, "old spelling of " + new_name)->group("");
  CLI::Option* current = app->get_option(new_name);
  // CLI11 leaves a hidden option's name out of its refusals, so the alias's checks name it themselves.
  for (int k = 0;; ++k) {
    try {
      const CLI::Validator check = *current->get_validator(k);
      alias->check(CLI::Validator(
          [check, old_name](std::string& text) {
            const std::string refusal = check(text);
            return refusal.empty() ? refusal : old_name + ": " + refusal;
          },
          check.get_description(), check.get_name()));
    } catch (const CLI::OptionNotFound&) {
      break;
    }
  }
  return alias;
}

// A subcommand that is listed in the contract but not built yet: it says so and exits 2.
void AddNotBuilt(CLI::App& app, const std::string& name, const std::string& summary, int issue);

// fvm calibrate BATCH --model N -o CAL.json (fvm/calibrate.cc).
void RegisterCalibrate(CLI::App& app);
// fvm correct --calibration CAL.json IN -o OUT (fvm/correct.cc).
void RegisterCorrect(CLI::App& app);
// fvm compare BATCH [--models ...] (fvm/compare.cc).
void RegisterCompare(CLI::App& app);
// fvm diagnose BATCH --model N (fvm/diagnose.cc).
void RegisterDiagnose(CLI::App& app);
// fvm info FILE [--json] (fvm/info.cc).
void RegisterInfo(CLI::App& app);
// fvm fit FILE [--artefact grid6x6|bar17] [-o centres.csv] [--json] (fvm/fit.cc).
void RegisterFit(CLI::App& app);
// fvm focus STACK -o height.x3p [--measure laplacian|tenengrad|variance] [--json] (fvm/focus.cc).
void RegisterFocus(CLI::App& app);
// fvm tiles plan|synthesize|simulate ... (fvm/tiles.cc).
void RegisterTiles(CLI::App& app);
// fvm tiles synthesize (fvm/tiles_synthesize.cc) and simulate (fvm/tiles_simulate.cc), under `tiles`.
void AddTilesSynthesize(CLI::App* tiles);
void AddTilesSimulate(CLI::App* tiles);
// fvm stitch --layout L.csv --overlap PCT -o P.csv [--pixel-mm S] (fvm/stitch.cc).
void RegisterStitch(CLI::App& app);
// fvm simulate fvm-batch ... (fvm/simulate.cc).
void RegisterSimulate(CLI::App& app);
// fvm simulate tracker -o DIR (fvm/simulate_tracker.cc), under `simulate`.
void RegisterSimulateTracker(CLI::App* simulate);
// fvm simulate scan -o DIR (fvm/simulate_scan.cc), under `simulate`.
void RegisterSimulateScan(CLI::App* simulate);

// fvm verify DATA.csv --chain XFYZ --order N --tool X,Y,Z [-o MACHINE.json] (fvm/verify.cc).
void RegisterVerify(CLI::App& app);
// fvm multilaterate READINGS.csv --stations S.json [--self-calibrate] [--angles] -o POINTS.csv (fvm/multilaterate.cc).
void RegisterMultilaterate(CLI::App& app);

// fvm uncertainty DATA.csv --runs R --seed S [--validate VAL.csv] [--json] (fvm/uncertainty.cc).
void RegisterUncertainty(CLI::App& app);

// fvm diff REF.csv TEST.csv [--pairs a:b,...] [--xy] [--json] (fvm/diff.cc).
void RegisterDiff(CLI::App& app);

// fvm testpiece design|verify (fvm/testpiece.cc).
void RegisterTestPiece(CLI::App& app);
// fvm simulate testpiece, registered by fvm simulate (fvm/testpiece.cc).
void RegisterSimulateTestPiece(CLI::App* simulate);

}  // namespace fvm::cli
