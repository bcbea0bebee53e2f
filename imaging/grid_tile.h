#pragma once
// A tile of a grid: its row and column, and where the grid (or the stage) puts its top-left corner, px (x right,
// y down, from the first tile).

#include <Eigen/Core>

namespace fvm::imaging {

struct GridTile {
  int row = 0, col = 0;
  Eigen::Vector2d nominal_px = Eigen::Vector2d::Zero();
};

}  // namespace fvm::imaging
