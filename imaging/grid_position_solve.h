#pragma once
// The positions of a grid's tiles from its pairs and a stage that moves by axes. A stage's error is shared: the x
// axis's error at a column is the same in every row, the y axis's straightness at a row the same in every column
// (its error is a function of each axis's position, as VDI 2617 writes it), and an axis that moves by steps adds
// them up. So each tile sits at its stage position plus its column's shared offset, plus its row's, plus its own
// repeatability; neighbouring columns' (rows') offsets differ by a step whose spread the pairs show. A block of tiles
// that hangs on a pair fixing one direction is then placed along the other by the tiles that share its rows and
// columns, not by a prior on each tile alone (issue 42's sparse cut tiles of a circuit board: a block of eight tiles
// 59 px off with u = 12 px, where its rows and columns were placed elsewhere in the grid).
//
// Pixel frame as in tile_registration.h: x right, y down, positions are tiles' top-left corners.

#include <Eigen/Core>
#include <vector>

#include "imaging/grid_tile.h"
#include "imaging/tile_pair_registration.h"
#include "imaging/tile_registration.h"

namespace fvm::imaging {

// The prior from a grid's steps (TileGridSteps): the spread of the east (south) offsets is the step between
// columns' (rows') offsets, less the two tiles' own repeatability it also holds; `fallback_px` where the pairs did
// not show a spread. Where they did not show the tiles' own repeatability, all of the pairs' spread is taken for it
// (the model's repeatability: the steps then keep only what exceeds it). Along an axis no pair fixes (machining
// marks along it), each tile on its own with the stage's `declared_px`.
StageAxesPrior StageAxesPriorOf(const TileGridSteps& steps, double fallback_px, double declared_px);

// Generalised least squares over the accepted pairs, p_b - p_a = offset weighted by each pair's information, and the
// stage: p = stage + column offset + row offset (own_px), column offsets a random walk from column to column
// (column_step_px), row offsets likewise; where the accepted pairs leave groups of tiles apart, a correction of the
// mean steps too (east_mean_px, south_mean_px); the first tile stays at its stage position exactly. Every tile's standard
// uncertainty is against the first tile, whether pairs link it there or only the stage does. `registered`: the
// images alone place the tile against its group's earliest along both axes to within registered_within_px (the
// plausible range; a tile linked through a pair that fixes one direction says false); `anchor` the earliest tile of
// the group of tiles the accepted pairs link.
TilePositions SolveGridPositions(const std::vector<GridTile>& tiles, const std::vector<Eigen::Vector2d>& stage_px,
                                 const std::vector<PairRegistration>& pairs, const StageAxesPrior& prior,
                                 double registered_within_px);

}  // namespace fvm::imaging
