// fvm uncertainty DATA.csv --chain XFYZ --order N --tool X,Y,Z --runs R --seed S [--validate VAL.csv] [--json]:
// Monte Carlo uncertainty of a machine-tool verification [GUM Supplement 1] (workflows/uncertainty.h), of a
// microscope stage's calibration (DATA a batch directory), or the ranking of tracker positions (--place-tracker).

#include <fmt/core.h>

#include <filesystem>

#include "core/input_error.h"
#include "core/progress.h"
#include "fvm/summary_output.h"
#include "fvm/commands.h"
#include "fvm/identify_options.h"
#include "fvm/machine_options.h"
#include "fvm/option_parsing.h"
#include "workflows/uncertainty_summary.h"

namespace fvm::cli {
namespace {

struct UncertaintyCommand {
  workflows::UncertaintyOptions options;
  std::string report;
  bool json = false;
};

// Writes the summary's report when asked and prints it, its JSON naming DATA.
void ShowUncertainty(const UncertaintyCommand& c, workflows::Summary summary) {
  AddSortedPath(summary.json, "data", c.options.machine.data);
  if (!c.report.empty() && summary.report) report::Write(c.report, *summary.report);
  fmt::print("{}", c.json ? summary.json.dump(2) + "\n" : summary.text);
}

// fvm uncertainty BATCH --model 27: the microscope stage, its centre noise resampled.
void RunStage(const UncertaintyCommand& c) {
  const workflows::UncertaintyOptions& o = c.options;
  if (!o.machine.validate.empty() || o.place_tracker) {
    throw InputError(fmt::format("{} is a batch directory: {} is for tracker readings (a batch names its validation "
                                 "placements in batch.json)",
                                 o.machine.data, o.machine.validate.empty() ? "--place-tracker" : "--validate"));
  }
  workflows::StageUncertaintyOptions job = o.stage;
  job.settings = Threaded(job.settings);
  const workflows::StageReference reference = workflows::IdentifyStageReference(job);
  Progress progress("monte carlo runs", o.monte_carlo.runs, ShowProgress());
  workflows::MonteCarloSettings mc = o.monte_carlo;
  mc.on_run_done = [&progress] { progress.Advance(); };
  const workflows::StageUncertainty u = workflows::RunStageMonteCarlo(job, reference, mc, o.Budget());
  progress.Finish();
  ShowUncertainty(c, workflows::Summarize(o, reference, u));
}

void Run(UncertaintyCommand c) {
  workflows::UncertaintyOptions& o = c.options;
  o.machine.threads = ThreadCount();
  o.monte_carlo.threads = Common().threads;
  o.Check();
  if (std::filesystem::is_directory(o.machine.data)) {
    o.stage.batch = o.machine.data;
    RunStage(c);
    return;
  }
  const workflows::MachineProblem problem = workflows::LoadMachineProblem(o.machine);
  const workflows::MachineReference reference = workflows::IdentifyMachineReference(problem, o.order);
  if (o.place_tracker) {
    workflows::TrackerPlacementOptions job = o.Placement();
    Progress progress("tracker positions", workflows::PlacementPositions(job), ShowProgress());
    job.on_position_done = [&progress] { progress.Advance(); };
    ShowUncertainty(c, workflows::Summarize(problem, o, workflows::PlaceTracker(problem, reference, job)));
    return;
  }
  Progress progress("monte carlo runs", o.monte_carlo.runs, ShowProgress());
  workflows::MonteCarloSettings mc = o.monte_carlo;
  mc.on_run_done = [&progress] { progress.Advance(); };
  const workflows::MachineUncertainty u = workflows::RunMachineMonteCarlo(problem, reference, mc, o.Budget());
  progress.Finish();
  ShowUncertainty(c, workflows::Summarize(problem, o, reference, u));
}

}  // namespace

void RegisterUncertainty(CLI::App& app) {
  auto command = std::make_shared<UncertaintyCommand>();
  workflows::UncertaintyOptions& o = command->options;
  CLI::App* sub = app.add_subcommand("uncertainty", "Monte Carlo uncertainty of a machine verification or stage calibration [GUM Supplement 1]");
  AddDetails(sub,
             "Identifies the machine from the readings as fvm verify does, takes that machine and tracker pose as the "
             "truth, and --runs times draws the readings again with the tracker's noise (normal in range, azimuth and "
             "elevation) and identifies them afresh. Reports the distribution of the final and validation mean errors "
             "over the runs, each point's 95 % radius and ellipsoid, distance errors over point pairs, and the "
             "[ISO/TS 15530-3] budget U = k sqrt(u_cal^2 + u_p^2 + u_b^2 + u_w^2). Run i draws from a stream seeded by "
             "(--seed, i): the same seed gives the same bits for any --threads. With a batch directory instead of "
             "readings, the microscope stage: the model (--model) is identified as fvm calibrate does, the stitched "
             "centres are drawn again around it with their noise, and the validation rms over the runs is shown next "
             "to the covariance-based prediction of fvm calibrate.");
  AddMachineOptions(sub, o.machine);
  sub->add_option("--order", o.order, "polynomial order of each error function")->check(Count(1, 3))->capture_default_str();
  sub->add_option("--runs", o.monte_carlo.runs, "Monte Carlo runs")->check(Count(1, 100'000))->capture_default_str();
  sub->add_option("--seed", o.monte_carlo.seed, "seed of the noise draws")->check(Within(kSeed))->capture_default_str();
  sub->add_option("--u-cal-um", o.u_cal_um, "standard uncertainty of the reference's calibration (um)")
      ->check(Within(0.0, 1e3, "um"))->capture_default_str();
  sub->add_option("--temperature-c", o.temperature_c, "half-range of the temperature, rectangular (C)")
      ->check(Within(0.0, 50.0, "C"))->capture_default_str();
  sub->add_option("--cte-per-k", o.cte_per_k, "expansion coefficient of the workpiece (1/K; aluminium 24e-6)")
      ->check(Within(0.0, 1e-3, "1/K"))->capture_default_str();
  sub->add_option("--k", o.k, "coverage factor")->check(Within(0.5, 10.0))->capture_default_str();
  sub->add_option("--report", command->report, "write an HTML report with SVG plots and CSV tables to this directory");
  sub->add_option("--model", o.stage.model.model, "microscope stage (DATA a batch): [Pérez 2019] model 9, 15, 27 or 42")
      ->check(CLI::IsMember({"9", "15", "27", "42"}))
      ->capture_default_str();
  sub->add_option("--terms", o.stage.model.terms, "microscope stage: your own model, TERM[:BASIS][:ORDER],... as in fvm calibrate");
  sub->add_option("--centre-noise-um", o.stage.centre_noise_um,
                  "microscope stage: standard deviation of a stitched centre per coordinate (default: the fit's residual)")
      ->check(Within(0.0, 1e3, "um"));
  AddIdentifyOptions(*sub, o.stage.settings);
  sub->add_option_function<std::string>(
         "--place-tracker",
         [&o](const std::string& text) {
           const std::vector<double> box = ParseNumbers(text, 6, "--place-tracker", "1000,-1500,0,2000,-500,800");
           o.place_tracker.emplace();
           std::copy(box.begin(), box.end(), o.place_tracker->begin());
           o.place_tracker_name = "--place-tracker " + text;
         },
                  "rank tracker positions on a grid of this box X0,Y0,Z0,X1,Y1,Z1 (machine frame, mm) by the largest "
                  "95 % radius over the points: covariance propagation for all, --runs Monte Carlo runs for the best")
      ->check(NumbersCheck(6, "--place-tracker", "1000,-1500,0,2000,-500,800"));
  sub->add_option("--place-steps", o.place_steps, "grid positions per axis of the --place-tracker box")
      ->check(Count(1, 50))->capture_default_str();
  sub->add_option("--place-confirm", o.place_confirm, "best positions the Monte Carlo confirms")
      ->check(Count(0, 100))->capture_default_str();
  sub->add_flag("--json", command->json, "print the result as JSON");
  sub->footer(
      "Example:\n  fvm simulate tracker --seed 1 --validation mesh:250,250,200 -o plan\n"
      "  fvm uncertainty plan/readings.csv --chain XFYZ --order 3 --tool 0,0,100 --fit-pose --runs 1000 --seed 1 \\\n"
      "    --validate plan/validation.csv --json\n"
      "  fvm uncertainty samples/bar17 --model 27 --runs 200");
  sub->callback([command] { Run(*command); });
}

}  // namespace fvm::cli
