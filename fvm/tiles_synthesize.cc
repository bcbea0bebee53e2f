// fvm tiles synthesize: tile sets with a known truth for fvm stitch (workflows/tiles_synthesize.h).

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "fvm/commands.h"
#include "fvm/option_parsing.h"
#include "imaging/tile_plan.h"
#include "workflows/tiles_synthesize.h"

namespace fvm::cli {
namespace {

struct SynthArgs {
  workflows::TilesSynthesizeOptions job;
  // --tile-px and --overlap (text: percent or fraction) reach `job` only when given: each texture has its defaults.
  int size = 256;
  std::string overlap = "0.2";
  bool size_given = false, overlap_given = false;
};

void RunSynthesize(SynthArgs& args) {
  if (args.size_given) args.job.tile_px = args.size;
  if (args.overlap_given) args.job.overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  const workflows::SynthesizedTileSet set = workflows::SynthesizeTileSet(args.job);
  fmt::print("{}", workflows::Summarize(set).text);
}

}  // namespace

void AddTilesSynthesize(CLI::App* tiles) {
  auto synth_args = std::make_shared<SynthArgs>();
  CLI::App* synth = tiles->add_subcommand(
      "synthesize", "synthetic overlapping tiles with known positions, for trying fvm stitch");
  synth->add_option("-o,--output", synth_args->job.output, "directory for the tiles, layout.csv and truth.csv")
      ->required();
  synth->add_option("--rows", synth_args->job.rows, "tile rows (default 3; with --artefact, as many as cover it)")->check(Count(1, 100));
  synth->add_option("--cols", synth_args->job.cols, "tile columns (default 3; with --artefact, as many as cover it)")->check(Count(1, 100));
  synth->add_option("--tile-px", synth_args->size, "tile width and height (px; --texture sparse: 245 x 183)")
      ->check(Count(16, 8192))
      ->capture_default_str()
      ->each([synth_args](const std::string&) { synth_args->size_given = true; });
  AddHiddenAlias(synth, "--size", synth_args->size, "--tile-px")->each([synth_args](const std::string&) {
    synth_args->size_given = true;
  });
  synth->add_option("--overlap", synth_args->overlap, "overlap of neighbouring tiles in percent, e.g. 20 (a value below 1 is read as a fraction: 0.2 = 20 %; --texture sparse: 6)")
      ->check(OverlapCheck("--overlap"))
      ->capture_default_str()
      ->each([synth_args](const std::string&) { synth_args->overlap_given = true; });
  synth->add_option("--stage-sigma-px", synth_args->job.stage_sigma_px,
                    "standard deviation of the stage error per axis (px; with --texture sparse the repeatability "
                    "on top of the systematic step error)")
      ->check(Within(0.0, 1e3, "px"))
      ->capture_default_str();
  synth->add_option("--texture", synth_args->job.texture,
                    "waves: a dense random texture; sparse: 16-bit blobs on a smooth background with shot noise, "
                    "5 x 5 tiles, a stage that steps 1.2 px long and drifts 4 px per column (like a real "
                    "microscope set of a sparse sample)")
      ->capture_default_str();
  AddHiddenAlias(synth, "--stage-error", synth_args->job.stage_sigma_px, "--stage-sigma-px");
  synth->add_option("--bits", synth_args->job.bits, "pixel type: 8, 16 (integer, the default) or 32 (float)")->check(Count(8, 32));
  synth->add_option("--artefact", synth_args->job.artefact,
                    "height-map tiles of grid6x6 or bar17 instead (float, mm, 10 um pixels, NaN on steep flanks), "
                    "with calottes.csv, the true calottes");
  synth->add_option("--seed", synth_args->job.seed, "random seed")->check(Within(kSeed))->capture_default_str();
  synth->footer("Tiles are cut from one random texture with 30 % vignetting and 3 % noise; truth.csv holds the "
                "true top-left corners, the first tile at 0,0. With --artefact they are cut from one height map of "
                "the artefact (0.5 um of roughness, 0.1 um of noise per tile) and the layout holds the stage "
                "positions: fvm tiles synthesize --artefact grid6x6 -o g && cd g && fvm stitch --layout layout.csv "
                "--overlap 20 --pixel-mm 0.01 -o p.csv --mosaic m.x3p && fvm fit m.x3p --artefact grid6x6 -o c.csv\n"
                "Example:\n  fvm tiles synthesize -o demo --rows 3 --cols 4 --tile-px 512 --overlap 20 --seed 1");
  synth->callback([synth_args] { RunSynthesize(*synth_args); });
}

}  // namespace fvm::cli
