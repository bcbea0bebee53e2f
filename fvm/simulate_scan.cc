// fvm simulate scan -o DIR: stitched calibration scans of a textured part on a stage with known errors (issue 21),
// with the layouts fvm calibrate --scan reads, the truth, and validation positions (workflows/simulate_scan.h).

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

#include "core/progress.h"
#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "workflows/simulate_scan.h"

namespace fvm::cli {
namespace {

struct SimulateScanArgs {
  std::string output;
  std::string heights = "-50";
  workflows::SimulateScanOptions options;
};

void Run(SimulateScanArgs args) {
  args.options.heights_mm = ParseNumberList(args.heights, "--heights", "-50,-40");
  std::optional<Progress> progress;
  const workflows::SimulatedScans scans = workflows::SimulateScans(
      args.options, args.output, [&](int tiles) { progress.emplace("rendering and writing tiles", tiles, ShowProgress()); },
      [&] { progress->Advance(); });
  progress->Finish();
  fmt::print("{}", workflows::Summarize(scans).text);
}

}  // namespace

void RegisterSimulateScan(CLI::App* simulate) {
  auto args = std::make_shared<SimulateScanArgs>();
  CLI::App* sub = simulate->add_subcommand(
      "scan", "stitched calibration scans (row, column, diagonal) of a textured part on a stage with known errors: "
              "tiles rendered where the stage really puts every pixel, layouts with encoder readings, truth.json, "
              "validation positions");
  AddDetails(sub,
      "Plans a row along X, a column along Y and a diagonal through the travel (fvm tiles plan --calibration-scan) "
      "and renders every tile where the stage really puts each pixel: at F(e) + C(e) d for pixel offset d from the "
      "optical axis, so the tiles turn with the guideways. The part is one texture for all paths; 16-bit counts "
      "with shot and read noise, or height maps. Writes DIR/<path>.csv (file,row,col,x,y,z: encoder readings of the "
      "tile centres, mm), DIR/<path>/tile_NNN.tif, DIR/truth.json (the stage, pixel size, texture) and "
      "DIR/validation.free.csv / validation.true.csv (positions as the encoders read them, and where the stage "
      "really puts the optical axis).");
  sub->add_option("-o,--output", args->output, "directory to write")->required();
  sub->add_option("--calibration-truth", args->options.calibration_truth,
                  "the stage: a truth.json of fvm simulate fvm-batch, or a calibration file; default: the stage of "
                  "fvm simulate fvm-batch --seed N");
  sub->add_option("--seed", args->options.seed, "random seed: the stage (without --calibration-truth), texture and noise")->check(Within(kSeed))->capture_default_str();
  sub->add_option("--lens", args->options.lens, "lens (field of view): 2.5x, 5x, 10x, ...")->capture_default_str();
  sub->add_option("--tile-px", args->options.tile_px, "square tiles of this many pixels")->check(Count(16, 8192))->capture_default_str();
  sub->add_option("--overlap", args->options.overlap, "overlap of consecutive tiles, percent or fraction")->check(OverlapCheck("--overlap"))->capture_default_str();
  sub->add_option("--length-mm", args->options.length_mm, "length of each path")->check(Within(kStepMm))->capture_default_str();
  sub->add_option("--heights", args->heights, "encoder z of each set of paths (mm), e.g. -50,-40 for a second height")
      ->check(NumbersCheck(0, "--heights", "-50,-40"))
      ->capture_default_str();
  sub->add_option("--texture", args->options.texture, "ground (fills the field), milled (a lay), blobs (sparse spots)")
      ->check(CLI::IsMember({"ground", "milled", "blobs"}))
      ->capture_default_str();
  sub->add_option("--tiles", args->options.tiles,
                  "grey: 16-bit images; heights: float TIFF height maps (mm, the part seen from each tile's focal "
                  "plane), whose overlaps give the stage's z steps too")
      ->check(CLI::IsMember({"grey", "heights"}))
      ->capture_default_str();
  sub->add_option("--periodic-um", args->options.periodic_um,
                  "a lead screw's cyclic error along X and Y the model cannot take (um); default: the truth file's, "
                  "else 0.3")
      ->check(Within(0.0, 1e3, "um"));
  sub->add_option("--period-mm", args->options.period_mm, "its period")->check(Within(kStepMm))->capture_default_str();
  sub->add_option("--distortion", args->options.distortion_px,
                  "radial field distortion of the objective, the same in every tile: px at the middle of each tile "
                  "edge (k1; barrel > 0, pincushion < 0); the truth is the stage's alone")
      ->check(Within(-50.0, 50.0, "px"));
  sub->add_option("--validation", args->options.validation, "validation positions to write")->check(Count(1, 1e6))->capture_default_str();
  sub->footer("Example:\n  fvm simulate scan -o scans --seed 1 --tile-px 256\n"
              "  fvm calibrate --scan scans/row.csv --scan scans/column.csv --scan scans/diagonal.csv --pixel-mm 0.01101563 "
              "--model 27 -o stage.json\n"
              "  fvm correct --calibration stage.json scans/validation.free.csv -o v.csv && fvm diff scans/validation.true.csv v.csv");
  sub->callback([args] { Run(*args); });
}

}  // namespace fvm::cli
