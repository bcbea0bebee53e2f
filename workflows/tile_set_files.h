#pragma once
// Tile sets as fvm stitch reads them, written by `fvm tiles plan`, `synthesize` and `simulate`: images named by
// their grid place and a layout.csv with the tile centres' stage positions when known.

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "imaging/grid_tile.h"
#include "imaging/io/tile_image.h"
#include "imaging/tile_plan.h"

namespace fvm::workflows {

// tile_r003_c012.tif
std::string TileFile(int row, int col);
// The layout of `tiles` (file,row,col,x,y: their centres in mm) headed by `comment` (its lines get '#').
std::string LayoutText(const std::vector<imaging::Tile>& tiles, const std::string& comment);
// A tile set for fvm stitch: every image as TileFile(row, col) in `directory`, and layout.csv headed by
// `comment` (its lines get '#'), with the stage positions of the tile centres when given. Returns the file names.
std::vector<std::string> WriteTileSet(const std::filesystem::path& directory,
                                      const std::vector<imaging::TileImage>& images,
                                      const std::vector<imaging::GridTile>& grid,
                                      const std::vector<Eigen::Vector2d>& stage_mm, imaging::TilePixelType type,
                                      const std::string& comment);

}  // namespace fvm::workflows
