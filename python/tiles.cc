// Tile jobs: `fvm tiles plan` (layouts with and without stitching, calibration scans), `fvm tiles simulate` (the
// [Pérez 2019] stitching strategies under a stage model) and `fvm tiles synthesize` (tile sets with a known truth),
// each returning fvm.Result: its summary the command's --json document, str() its text.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>

#include "core/file_io.h"
#include "core/input_error.h"
#include "imaging/tile_plan.h"
#include "python/bindings.h"
#include "workflows/stitching_strategies.h"
#include "workflows/tiles_plan.h"
#include "workflows/tiles_synthesize.h"

namespace fvm::python {
namespace {

// An overlap as the commands read one: a fraction, or percent from 1 up.
double OverlapFraction(double overlap) { return overlap >= 1.0 ? overlap / 100.0 : overlap; }

std::string PathText(const std::optional<std::filesystem::path>& path) { return path ? path->string() : std::string(); }

workflows::Summary TilesPlan(const std::string& lens, double fov_mm, const std::optional<std::array<double, 4>>& region,
                             double overlap, const std::optional<std::filesystem::path>& features,
                             const std::string& artefact, double radius_mm, double seconds_per_tile,
                             const std::pair<int, int>& tile_px, int bytes_per_pixel, bool calibration_scan,
                             const std::pair<double, double>& travel, double length_mm,
                             const std::vector<double>& heights, const std::optional<std::filesystem::path>& scan_dir,
                             const std::optional<std::filesystem::path>& layout,
                             const std::optional<std::filesystem::path>& free_layout) {
  workflows::TilesPlanOptions o;
  o.lens = lens;
  o.fov_mm = fov_mm;
  if (region) o.region = imaging::Region{(*region)[0], (*region)[1], (*region)[2], (*region)[3]};
  o.overlap = OverlapFraction(overlap);
  o.features = PathText(features);
  o.artefact = artefact;
  o.radius_mm = radius_mm;
  o.seconds_per_tile = seconds_per_tile;
  std::tie(o.tile_width_px, o.tile_height_px) = tile_px;
  o.bytes_per_pixel = bytes_per_pixel;
  o.calibration_scan = calibration_scan;
  std::tie(o.travel_width_mm, o.travel_height_mm) = travel;
  o.length_mm = length_mm;
  o.heights_mm = heights;
  o.scan_dir = PathText(scan_dir);
  py::gil_scoped_release release;
  const workflows::TilesPlan plan = workflows::PlanTiles(o);
  if (calibration_scan) {
    workflows::WriteScanLayouts(plan);
  } else {
    const std::string free = free_layout ? workflows::StitchingFreeLayoutText(plan) : "";
    if (layout) WriteFileAtomically(*layout, workflows::StitchedLayoutText(plan));
    if (free_layout) WriteFileAtomically(*free_layout, free);
  }
  return workflows::Summarize(plan);
}

workflows::Summary TilesSimulate(const std::filesystem::path& calibration, const std::string& lens, double overlap,
                                 const std::vector<double>& from, const std::vector<double>& to, bool render,
                                 int tile_px, const std::optional<std::filesystem::path>& tiles, std::uint64_t seed,
                                 int threads) {
  workflows::StitchingStrategiesOptions o;
  o.calibration = calibration.string();
  o.lens = lens;
  o.overlap = overlap;
  o.from = from;
  o.to = to;
  o.render = render;
  o.tile_px = tile_px;
  o.tiles = PathText(tiles);
  o.seed = seed;
  o.threads = threads;
  py::gil_scoped_release release;
  return workflows::Summarize(workflows::SimulateStitchingStrategies(o));
}

workflows::Summary TilesSynthesize(const std::filesystem::path& output, int rows, int cols,
                                   const std::optional<int>& tile_px, const std::optional<double>& overlap,
                                   double stage_sigma_px, int bits, const std::string& artefact,
                                   const std::string& texture, std::uint64_t seed) {
  workflows::TilesSynthesizeOptions o;
  o.output = output.string();
  o.rows = rows;
  o.cols = cols;
  o.tile_px = tile_px;
  if (overlap) o.overlap = OverlapFraction(*overlap);
  o.stage_sigma_px = stage_sigma_px;
  o.bits = bits;
  o.artefact = artefact;
  o.texture = texture;
  o.seed = seed;
  py::gil_scoped_release release;
  return workflows::Summarize(workflows::SynthesizeTileSet(o));
}

}  // namespace

void BindTiles(py::module_& m) {
  const workflows::TilesPlanOptions plan;
  m.def("tiles_plan", &TilesPlan, py::arg("lens") = plan.lens, py::arg("fov_mm") = plan.fov_mm,
        py::arg("region") = std::nullopt, py::arg("overlap") = plan.overlap, py::arg("features") = std::nullopt,
        py::arg("artefact") = plan.artefact, py::arg("radius_mm") = plan.radius_mm,
        py::arg("seconds_per_tile") = plan.seconds_per_tile,
        py::arg("tile_px") = std::make_pair(plan.tile_width_px, plan.tile_height_px),
        py::arg("bytes_per_pixel") = plan.bytes_per_pixel, py::arg("calibration_scan") = plan.calibration_scan,
        py::arg("travel") = std::make_pair(plan.travel_width_mm, plan.travel_height_mm),
        py::arg("length_mm") = plan.length_mm, py::arg("heights") = plan.heights_mm, py::arg("scan_dir") = std::nullopt,
        py::arg("layout") = std::nullopt, py::arg("free_layout") = std::nullopt,
        "Plans tile layouts, as `fvm tiles plan` does: the stitched grid of a region (x0, y0, x1, y1 mm; by default "
        "the features' bounding box) and the stitching-free tiles that cover the calottes of `features` (a centre "
        "export) or `artefact` (grid6x6, bar17), with scan time and data volume; or, with calibration_scan, the "
        "row, column and diagonal paths over the travel (W, H mm) for `fvm calibrate --scan`. layout, free_layout, "
        "scan_dir: write the layouts as the command's -o, --free-layout and --scan-dir do. Returns fvm.Result "
        "(.summary: the command's --json document).\n\nExample:\n"
        "    >>> fvm.tiles_plan(lens='10x', artefact='grid6x6', overlap=13).summary['stitched']['tiles']\n    225");
  const workflows::StitchingStrategiesOptions strategies;
  m.def("tiles_simulate", &TilesSimulate, py::arg("calibration"), py::arg("lens") = strategies.lens,
        py::arg("overlap") = strategies.overlap, py::arg("from_") = strategies.from, py::arg("to") = strategies.to,
        py::arg("render") = strategies.render, py::arg("tile_px") = strategies.tile_px,
        py::arg("tiles") = std::nullopt, py::arg("seed") = strategies.seed, py::arg("threads") = strategies.threads,
        "The end-to-end distance error of the six stitching strategies of [Pérez 2019] under the stage model of "
        "`calibration` (a file written by `fvm calibrate -o`), as `fvm tiles simulate` computes it; ``from_`` and ``to``: "
        "the first and last calotte (x, y, z mm). render: also on tiles rendered where the stage puts them, "
        "registered and fitted; tiles: a directory for the rendered row (16-bit TIFFs and layout.csv). Returns "
        "fvm.Result (.summary: the command's --json document).\n\nExample:\n"
        "    >>> [c['diff_um'] for c in fvm.tiles_simulate('stage.json').summary['cases']]");
  const workflows::TilesSynthesizeOptions synth;
  m.def("tiles_synthesize", &TilesSynthesize, py::arg("output"), py::arg("rows") = synth.rows,
        py::arg("cols") = synth.cols, py::arg("tile_px") = synth.tile_px, py::arg("overlap") = synth.overlap,
        py::arg("stage_sigma_px") = synth.stage_sigma_px, py::arg("bits") = synth.bits,
        py::arg("artefact") = synth.artefact, py::arg("texture") = synth.texture, py::arg("seed") = synth.seed,
        "Writes a tile set with a known truth into the directory `output`, as `fvm tiles synthesize -o` does: "
        "texture 'waves' (3 x 3 tiles of 256 px by default; bits 8, 16 or 32) or 'sparse' (5 x 5 of 245 x 183 px "
        "on a drifting stage), or height tiles of an artefact (grid6x6, bar17) with calottes.csv; layout.csv for "
        "fvm.stitch and truth.csv. rows, cols 0, tile_px and overlap None: the texture's defaults. Returns "
        "fvm.Result (.summary: kind, tiles, width_px, height_px, overlap; str(): the command's line).\n\nExample:\n"
        "    >>> fvm.tiles_synthesize('demo', rows=3, cols=4, seed=1)\n"
        "    >>> fvm.stitch('demo/layout.csv', overlap=20)['positions']");
}

}  // namespace fvm::python
