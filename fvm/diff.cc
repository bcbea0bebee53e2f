// fvm diff: how far a test export of an artefact is from a reference export of it, calotte by calotte and as
// distances between calottes (workflows/diff.h).

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "fvm/commands.h"
#include "fvm/summary_output.h"
#include "workflows/diff.h"

namespace fvm::cli {
namespace {

struct DiffArgs {
  std::string ref;
  std::string test;
  bool json = false;
  workflows::DiffOptions options;
};

void RunDiff(const DiffArgs& args) {
  const workflows::DiffResult result = workflows::DiffFiles(
      args.ref, args.test, args.options, [](const std::string& w) { fmt::print(stderr, "fvm diff: warning: {}\n", w); });
  PrintSummary(workflows::Summarize(result), args.json, {{"ref", args.ref, "distance"}, {"test", args.test, "distance"}});
}

}  // namespace

void RegisterDiff(CLI::App& app) {
  auto args = std::make_shared<DiffArgs>();
  CLI::App* sub = app.add_subcommand("diff", "per-calotte and distance differences between two exports");
  AddDetails(sub,
      "Per-calotte differences TEST - REF (dx, dy, dz, |d| in um) for the calottes in both centre exports, and for "
      "each pair of calottes their distance in REF and in TEST (mm) and its change (um). Calottes in only one file "
      "are left out with a warning.");
  sub->add_option("REF", args->ref, "reference centre export (CSV id,x,y,z in mm), e.g. the stitched one")
      ->required();
  sub->add_option("TEST", args->test, "centre export to compare with it")->required();
  sub->add_option("--pairs", args->options.pairs,
                  "calotte pairs a:b whose distances to compare, e.g. 1:6,1:31 (default: the first common calotte "
                  "with every other one)");
  sub->add_flag("--xy", args->options.xy, "distances in the XY plane, z ignored (as the stitching tables of [Pérez 2019])");
  sub->add_flag("--json", args->json,
                "print one JSON document {\"calottes\": [{\"id\", \"dx_um\", \"dy_um\", \"dz_um\", \"d_um\"}], "
                "\"pairs\": [{\"a\", \"b\", \"ref_mm\", \"test_mm\", \"diff_um\"}]}");
  sub->footer(
      "Example: fvm diff samples/stitching-strategies/x/a.csv samples/stitching-strategies/x/b.csv --pairs 1:6 --xy");
  sub->callback([args] { RunDiff(*args); });
}

}  // namespace fvm::cli
