#include "workflows/tile_set_files.h"

#include <fmt/core.h>

#include <optional>
#include <sstream>

#include "core/file_io.h"
#include "imaging/io/tile_layout.h"

namespace fvm::workflows {

std::string TileFile(int row, int col) { return fmt::format("tile_r{:03d}_c{:03d}.tif", row, col); }

std::string LayoutText(const std::vector<imaging::Tile>& tiles, const std::string& comment) {
  std::vector<imaging::TileLayoutEntry> entries;
  for (const auto& t : tiles) entries.push_back({TileFile(t.row, t.col), t.row, t.col, t.centre_mm, 0, std::nullopt});
  return "# " + comment + "\n" + imaging::FormatTileLayout(entries);
}

// A tile set for fvm stitch: every image as TileFile(row, col) in `directory`, and layout.csv headed by
// `comment` (its lines get '#'), with the stage positions of the tile centres when given. Returns the file names.
std::vector<std::string> WriteTileSet(const std::filesystem::path& directory,
                                      const std::vector<imaging::TileImage>& images,
                                      const std::vector<imaging::GridTile>& grid,
                                      const std::vector<Eigen::Vector2d>& stage_mm, imaging::TilePixelType type,
                                      const std::string& comment) {
  std::filesystem::create_directories(directory);
  std::vector<imaging::TileLayoutEntry> entries;
  std::vector<std::string> files;
  for (size_t i = 0; i < images.size(); ++i) {
    const imaging::GridTile& t = grid[i];
    files.push_back(TileFile(t.row, t.col));
    imaging::WriteTileImage(directory / files.back(), images[i], type);
    entries.push_back({files.back(), t.row, t.col,
                       stage_mm.empty() ? std::nullopt : std::optional<Eigen::Vector2d>(stage_mm[i]), 0, std::nullopt});
  }
  std::string header;
  std::stringstream lines(comment);
  for (std::string line; std::getline(lines, line);) header += "# " + line + "\n";
  WriteFileAtomically(directory / "layout.csv", header + imaging::FormatTileLayout(entries));
  return files;
}

}  // namespace fvm::workflows
