#include "workflows/stitch.h"

#include <fmt/core.h>

#include <cmath>
#include <set>
#include <string>
#include <utility>

#include "core/input_error.h"

namespace fvm::workflows {

void StitchOptions::Check() const {
  if (!(overlap > 0.0 && overlap < 1.0)) {
    throw InputError(fmt::format("--overlap {}: give the nominal overlap of neighbouring tiles as a fraction in (0, 1), "
                                 "e.g. 0.2 for 20 %",
                                 overlap));
  }
  if (pixel_mm < 0.0 || !std::isfinite(pixel_mm)) {
    throw InputError(fmt::format("--pixel-mm {}: give the pixel size in mm, e.g. 0.000875", pixel_mm));
  }
  if (!(registration.min_quality >= -1.0 && registration.min_quality <= 1.0)) {
    throw InputError("--min-quality: give a correlation in [-1, 1], e.g. 0.5");
  }
  if (!(registration.stage_sigma_px > 0.0) || !std::isfinite(registration.stage_sigma_px)) {
    throw InputError("--stage-sigma-px: give the stage's positioning error over the grid in pixels, e.g. 2");
  }
  if (threads < 0) throw InputError(fmt::format("--threads {}: give 0 (all cores) or more", threads));
}

std::vector<imaging::GridTile> NominalGrid(const imaging::TileLayout& layout, int width_px, int height_px,
                                           const StitchOptions& options, bool* from_stage) {
  const double width = static_cast<double>(width_px), height = static_cast<double>(height_px);
  const bool stage = options.pixel_mm > 0.0 && layout.tiles.front().stage_mm.has_value();
  // A Fiji tile configuration's positions are in px already: the stage positions, whatever the pixel size.
  const bool in_px = !stage && layout.tiles.front().nominal_px.has_value();
  const auto& first = layout.tiles.front();
  std::vector<imaging::GridTile> grid;
  for (const auto& tile : layout.tiles) {
    Eigen::Vector2d nominal;
    if (in_px) {
      nominal = tile.nominal_px.value() - *first.nominal_px;
    } else if (stage) {
      nominal = Eigen::Vector2d(tile.stage_mm->x() - first.stage_mm->x(), first.stage_mm->y() - tile.stage_mm->y()) /
                options.pixel_mm;
    } else {
      nominal = Eigen::Vector2d((tile.col - first.col) * width * (1.0 - options.overlap),
                                (tile.row - first.row) * height * (1.0 - options.overlap));
    }
    grid.push_back({tile.row, tile.col, nominal});
  }
  if (from_stage) *from_stage = stage || in_px;
  return grid;
}

int CountGridPairs(const std::vector<imaging::GridTile>& grid) {
  return static_cast<int>(imaging::GridNeighbourPairs(grid).size());
}

void DescribeRegistration(StitchResult& s, const std::vector<std::string>& files) {
  const imaging::RegistrationResult& r = s.registration;
  s.accepted = s.ambiguous = 0;
  for (const auto& pair : r.pairs) s.accepted += pair.accepted, s.ambiguous += pair.accepted && pair.ambiguous;
  s.overruled.clear();
  for (const auto& o : r.loops.overruled) {
    const auto& pair = r.pairs[static_cast<size_t>(o.pair)];
    s.overruled.push_back(files[static_cast<size_t>(pair.a)] + " - " + files[static_cast<size_t>(pair.b)] + ": " +
                          o.Text());
  }
  s.unresolved = r.pairs_unresolved;
  s.mostly_unresolved = r.MostlyUnresolved();
  s.at_stage_position.clear(), s.stage_along_one_axis.clear();
  for (size_t i = 0; i < files.size(); ++i) {
    if (r.positions.registered[i]) continue;
    if (i > 0 && r.positions.anchor[i] == 0) {
      // Linked to the first tile by images, but along one direction only (parallel marks, traces): the stage's rows
      // and columns place it along the other.
      s.stage_along_one_axis.push_back(files[i]);
    } else {
      s.at_stage_position.push_back(files[i]);
    }
  }
}

StitchResult StitchTiles(const imaging::TileLayout& layout, const std::vector<imaging::TileImage>& images,
                         const StitchOptions& options, const std::function<void(int, int)>& on_pair) {
  StitchResult s;
  s.grid = NominalGrid(layout, static_cast<int>(images.front().cols()), static_cast<int>(images.front().rows()), options,
                       &s.from_stage);
  s.origin_mm = layout.tiles.front().stage_mm.value_or(Eigen::Vector2d::Zero());
  imaging::SetImagingThreads(options.threads);
  s.registration = imaging::RegisterTileGrid(images, s.grid, options.registration, on_pair);
  s.overlap_ncc = imaging::NeighbourOverlapNcc(images, s.grid, s.registration.positions.positions_px);
  double sum = 0.0;
  for (const auto& o : s.overlap_ncc) {
    if (std::isfinite(o.correlation.ncc)) sum += o.correlation.ncc, ++s.ncc_pairs;
  }
  if (s.ncc_pairs > 0) s.mean_overlap_ncc = sum / s.ncc_pairs;
  std::vector<std::string> files;
  for (const auto& tile : layout.tiles) files.push_back(tile.file);
  for (const size_t i : imaging::TilesWithoutNeighbour(layout)) {
    const imaging::TileLayoutEntry& tile = layout.tiles[i];
    s.without_neighbour.push_back(fmt::format("{} (row {} col {})", tile.file, tile.row, tile.col));
  }
  DescribeRegistration(s, files);
  return s;
}

std::string StitchResult::UnresolvedWarning() const {
  if (!mostly_unresolved) return {};
  return std::to_string(unresolved) + " of " + std::to_string(registration.pairs.size()) +
         " pairs are unresolved (a quarter or more): the positions of the tiles they leave rest on the stage, "
         "not on the images; check the overlap, the focus and the texture";
}

}  // namespace fvm::workflows
