#include "workflows/stitching_strategies.h"

#include <fmt/core.h>

#include <map>
#include <stdexcept>

#include "core/input_error.h"
#include "imaging/tile_plan.h"
#include "imaging/tile_registration.h"
#include "stage/io/calibration_file.h"
#include "workflows/tile_set_files.h"

namespace fvm::workflows {
namespace {

using Json = nlohmann::ordered_json;

Eigen::Vector3d Point(const std::vector<double>& v) { return {v[0], v[1], v[2]}; }

// The rendered row as a tile set for fvm stitch: 16-bit TIFFs and a layout whose x, y are the encoder readings of
// the tile centres, so that stitching them with the pixel size reproduces case a.
void WriteRenderedRow(const artefacts::RenderedStrategies& row, const artefacts::RenderedStrategyOptions& options,
                      const std::filesystem::path& directory) {
  std::vector<imaging::GridTile> grid;
  for (size_t i = 0; i < row.images.size(); ++i) grid.push_back({0, static_cast<int>(i), Eigen::Vector2d::Zero()});
  WriteTileSet(directory, row.images, grid, row.encoder_centres_mm, imaging::TilePixelType::kUint16,
               fmt::format("fvm tiles simulate --render --seed {}: the row of {} tiles of {} px, {:.6f} mm per px, "
                           "x,y = encoder readings of the tile centres (mm). Stitch with:\nfvm stitch --layout "
                           "layout.csv --overlap {:g} --pixel-mm {:.9g} -o positions.csv",
                           options.seed, row.images.size(), options.tile_px, row.pixel_mm,
                           options.geometry.overlap * 100, row.pixel_mm));
}

// The published differences ([Pérez 2019] Table 1, 6 x 6 grid, 10x lens, calottes 1 and 6), for comparison.
const std::map<char, double>& Published() {
  static const std::map<char, double> published = {{'b', -14.6}, {'c', -1.5}, {'d', -8.9}, {'e', -14.8}, {'f', -15.0}};
  return published;
}

Json StrategiesJson(const StitchingStrategies& s) {
  const artefacts::RenderedStrategyOptions& o = s.rendering;
  Json doc;
  doc["calibration"] = s.options.calibration;
  doc["fov_mm"] = o.geometry.fov_mm;
  doc["overlap"] = o.geometry.overlap;
  if (s.rendered) {
    doc["rendered"] = {{"tile_px", o.tile_px},
                       {"pixel_um", s.rendered->pixel_mm * 1e3},
                       {"row_tiles", s.rendered->row_tiles},
                       {"pair_rms_px", s.rendered->pair_rms_px},
                       {"rejected_pairs", s.rendered->rejected_pairs},
                       {"seed", o.seed}};
  }
  for (size_t k = 0; k < s.results.size(); ++k) {
    const artefacts::StrategyResult& r = s.results[k];
    Json c = {{"case", std::string(1, r.id)}, {"description", r.description},
              {"tiles", r.tiles},           {"encoder_tiles", r.encoder_tiles},
              {"distance_mm", r.distance_mm}, {"diff_um", r.distance_error_um}};
    if (s.rendered) {
      const artefacts::RenderedStrategyResult& g = s.rendered->cases[k];
      c["rendered"] = {{"encoder_tiles", g.result.encoder_tiles}, {"distance_mm", g.result.distance_mm},
                       {"diff_um", g.result.distance_error_um},  {"pairs", g.pairs},
                       {"accepted_pairs", g.accepted_pairs}};
    }
    doc["cases"].push_back(c);
  }
  return doc;
}

std::string StrategiesText(const StitchingStrategies& s) {
  const artefacts::RenderedStrategyOptions& o = s.rendering;
  const std::optional<artefacts::RenderedStrategies>& rendered = s.rendered;
  std::string text = fmt::format(
      "stitching strategies over {:.3f} mm with the {} lens ({} mm field, {:.0f} % overlap), stage model {} from {}\n",
      (Point(s.options.to) - Point(s.options.from)).norm(), s.options.lens, o.geometry.fov_mm, o.geometry.overlap * 100,
      s.model, s.options.calibration);
  if (rendered) {
    text += fmt::format("rendered: {} tiles of {} px ({:.3f} um / px), neighbour pairs registered to {:.3f} px rms "
                        "({:.3f} um), {} rejected; seed {}\n",
                        rendered->row_tiles, o.tile_px, rendered->pixel_mm * 1e3, rendered->pair_rms_px,
                        rendered->pair_rms_px * rendered->pixel_mm * 1e3, rendered->rejected_pairs, o.seed);
  }
  text += fmt::format("\n  {:<4} {:<36} {:>5} {:>13} {:>10} {:>12} {:>14}\n", "case", "strategy", "tiles", "distance mm",
                      "diff um", rendered ? "rendered um" : "", "published um");
  for (size_t k = 0; k < s.results.size(); ++k) {
    const artefacts::StrategyResult& r = s.results[k];
    const auto p = Published().find(r.id);
    text += fmt::format("  {:<4} {:<36} {:>5} {:>13.4f} {:>10.1f} {:>12} {:>14}\n", r.id, r.description, r.tiles,
                        r.distance_mm, r.distance_error_um,
                        rendered ? fmt::format("{:.1f}", rendered->cases[k].result.distance_error_um) : "",
                        p == Published().end() ? "-" : fmt::format("{:.1f}", p->second));
  }
  text += "\n  A tile that cannot be registered to its neighbour falls back to the encoders and carries the stage "
          "error there;\n  the error grows with the distance from the first tile to the last such tile.\n";
  if (rendered) {
    text += "  'rendered' comes from images: tiles rendered where the stage really is, registered, and the calottes "
            "fitted in\n  their tiles; it differs from 'diff' by the registration and fit noise.\n";
  }
  return text;
}

}  // namespace

void StitchingStrategiesOptions::Check() const {
  if (from.size() != 3) throw InputError("--from: give the first calotte as x,y,z in mm");
  if (to.size() != 3) throw InputError("--to: give the last calotte as x,y,z in mm");
  if (tile_px < 16 || tile_px > 8192) throw InputError(fmt::format("--tile-px {}: give 16 to 8192 px", tile_px));
  if (!(overlap > 0.0 && overlap < 100.0)) {
    throw InputError(fmt::format("--overlap {}: give the overlap in percent, e.g. 20, or a fraction, e.g. 0.2", overlap));
  }
  if (threads < 0) throw InputError(fmt::format("--threads {}: give 0 (all cores) or more", threads));
}

StitchingStrategies SimulateStitchingStrategies(const StitchingStrategiesOptions& options,
                                                const std::function<void()>& before_rendering) {
  options.Check();
  imaging::SetImagingThreads(options.threads);  // render registers tiles on OpenCV's pool
  StitchingStrategies s;
  s.options = options;
  const stage::Calibration cal = stage::ReadCalibration(options.calibration);
  s.model = cal.model;
  artefacts::RenderedStrategyOptions& rendering = s.rendering;
  rendering.geometry.fov_mm = imaging::FindLens(options.lens).fov_mm;
  rendering.geometry.overlap = options.overlap > 1.0 ? options.overlap / 100.0 : options.overlap;
  rendering.tile_px = options.tile_px;
  rendering.seed = options.seed;
  if (!options.tiles.empty() && !options.render) throw InputError("--tiles needs --render");
  try {
    if (options.render) {
      if (before_rendering) before_rendering();
      s.rendered = artefacts::SimulateRenderedStrategies(cal.layout, cal.values, Point(options.from), Point(options.to),
                                                         rendering);
      for (const artefacts::RenderedStrategyResult& c : s.rendered->cases) s.results.push_back(c.coordinates);
    } else {
      s.results = artefacts::SimulateStitchingStrategies(cal.layout, cal.values, Point(options.from),
                                                         Point(options.to), rendering.geometry);
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("fvm tiles simulate: ") + e.what());
  }
  if (!options.tiles.empty()) WriteRenderedRow(*s.rendered, rendering, options.tiles);
  return s;
}

Summary Summarize(const StitchingStrategies& strategies) {
  return {StrategiesJson(strategies), StrategiesText(strategies), std::nullopt};
}

}  // namespace fvm::workflows
