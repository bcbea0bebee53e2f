#pragma once
// What stitching strategies do to a measured distance ([Pérez 2019] section 1.2, Tables 1 and 2).
//
// A row of tiles runs from the tile that holds the first calotte to the one that holds the last. The first tile
// is placed by the encoders; each following tile is registered to its neighbour, so it inherits its neighbour's
// placement; a tile whose neighbour is missing cannot be registered and falls back to the encoders. Encoders at
// command q report a point that really is at F(q), so a tile placed by encoders at q, and every tile registered
// after it, reports coordinates off by -e(q) = q - F(q). The distance error between the two calottes is therefore
// set by the stage error at the last tile placed by encoders, against the first.
//
// This file works on coordinates; artefacts/rendered_stitching_strategy.h renders the tiles and registers them.

#include <Eigen/Core>
#include <set>
#include <string>
#include <vector>

#include "stage/parameter_layout.h"

namespace fvm::artefacts {

struct StrategyOptions {
  double fov_mm = 1.62;   // 10x lens ([Pérez thesis] Table 5.2)
  double overlap = 0.2;   // of neighbouring tiles ([Pérez thesis] 5.7.2)
  void Check() const;     // throws std::invalid_argument
};

// The row of tiles between two calottes: where each tile really looks and what the encoders say there.
struct StrategyRow {
  std::vector<Eigen::Vector3d> centres;   // true points under the tile centres; the first and last on the calottes
  std::vector<Eigen::Vector3d> commands;  // the stage commands (encoder readings) that put the tiles there
};

// Tiles at most fov x (1 - overlap) apart. Throws std::invalid_argument when the calottes coincide,
// std::runtime_error when the stage model cannot be inverted along the row.
StrategyRow PlanStrategyRow(const stage::ParameterLayout& layout, const std::vector<double>& values,
                            const Eigen::Vector3d& first, const Eigen::Vector3d& last, const StrategyOptions& options);

struct StrategyCase {
  char id = 'a';  // the published case letter
  std::string description;
  std::set<int> missing;  // tile indices not taken; never the first or the last
};

// The six published strategies for a row of n >= 2 tiles: (a) all tiles stitched, (b) only the two end tiles,
// (c) the tile after the first missing, (d) a middle tile missing, (e) the tile before the last missing, (f) every
// other tile missing.
std::vector<StrategyCase> StitchingStrategyCases(int n);

struct StrategyResult {
  char id = 'a';                      // the published case letter
  std::string description;
  int tiles = 0;                      // tiles taken
  std::vector<int> encoder_tiles;     // indices (0 = first) of tiles placed by the encoders
  double distance_mm = 0.0;           // measured distance between the two calottes
  double distance_error_um = 0.0;     // measured - true
};

// The six strategies on coordinates over a planned row (its first and last centres are the calottes).
std::vector<StrategyResult> SimulateStitchingStrategies(const StrategyRow& row);

// The same, planning the row. `first` and `last` are the calottes' true positions (mm); the stage error model is
// F of `layout` with `values`.
std::vector<StrategyResult> SimulateStitchingStrategies(const stage::ParameterLayout& layout,
                                                        const std::vector<double>& values, const Eigen::Vector3d& first,
                                                        const Eigen::Vector3d& last, const StrategyOptions& options = {});

}  // namespace fvm::artefacts
