#pragma once
// `fvm stitch` as a whole, for every front end: a layout's tiles read as the command reads them, registered
// (workflows/stitch.h), with --distortion placed without the objective's field (workflows/stitch_distortion.h), and
// what the command writes from them: the positions CSV, the tiles resampled without the field, the fused mosaic.
// Its summary (the --json document and the printed text) is in workflows/stitch_summary.h.

#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "imaging/io/tile_image.h"
#include "imaging/io/tile_layout.h"
#include "imaging/tile_mosaic.h"
#include "workflows/stitch.h"
#include "workflows/stitch_distortion.h"

namespace fvm::workflows {

struct StitchLayoutOptions {
  StitchOptions stitch;  // --overlap, --pixel-mm, --min-quality, --stage-sigma-px, --threads
  // --distortion [ORDER] (a field identified) or --distortion-file F (`known`: positions only); none: rigid.
  std::optional<StitchDistortionOptions> distortion;
  void Check() const;  // StitchOptions::Check
};

// A layout and its tiles as fvm stitch reads them: complete grid, images of one size, colour averaged to grey.
struct LayoutTiles {
  imaging::TileLayout layout;
  std::vector<imaging::TileImage> images;
  imaging::TilePixelType pixel_type = imaging::TilePixelType::kFloat;  // the first tile's
};
// Throws InputError naming the layout's line and tile (imaging/io/tile_layout.h). The tiles decoded on `threads`
// threads (0: all cores). A Fiji tile configuration (imaging/io/fiji_tile_configuration.h) is read as a layout, its
// rows and columns clustered with the pitch the tile size and `overlap` (a fraction) give, or, with overlap 0, the
// pitch its positions' gaps show.
LayoutTiles ReadLayoutTiles(const std::filesystem::path& layout, int threads = 0, double overlap = 0.0);

struct StitchedLayout {
  std::vector<std::string> files;  // the layout's tiles, in its order
  int width_px = 0, height_px = 0;
  StitchOptions options;
  StitchResult rigid;
  std::optional<StitchDistortionResult> field;  // with a distortion
  // With a field whose pairs registered again on the undistorted tiles (field->pairs_registered_undistorted > 0):
  // that registration (field->registration) described as `rigid` describes the first (the overlap correlation stays
  // the raw tiles' at the rigid positions, the measure before the field).
  std::optional<StitchResult> registered_undistorted;
  // The registration the positions rest on: which pairs placed them, which tiles the images place (the positions
  // CSV's `registered`), which rest on the stage. Every summary reads this one.
  const StitchResult& Registered() const;
  // The positions and their standard uncertainties: the undistorted tiles' with a field, else the rigid ones.
  const std::vector<Eigen::Vector2d>& PositionsPx() const;
  const std::vector<Eigen::Vector2d>& SigmaPx() const;
};

// `images[i]` is the layout's tile i. Throws InputError "--distortion, LAYOUT: ..." when the overlaps cannot
// determine the field. `on_pair` as StitchTiles.
StitchedLayout StitchLayout(const imaging::TileLayout& layout, const std::vector<imaging::TileImage>& images,
                            const StitchLayoutOptions& options,
                            const std::function<void(int done, int total)>& on_pair = {});
// Registration pairs StitchLayout will report to `on_pair` (the total of a progress count).
int StitchPairCount(const imaging::TileLayout& layout, const std::vector<imaging::TileImage>& images,
                    const StitchOptions& options);

// file,x,y[,x_mm,y_mm],registered,u_x,u_y (x_mm, y_mm with the pixel size: stage frame, +Y up).
std::string PositionsCsv(const StitchedLayout& stitched);
// The same positions as Fiji's registered tile configuration (`name; ; (x, y)`, px), for `-o NAME.txt`: Fiji's
// Grid/Collection stitching opens them. With a field, the positions of the undistorted tiles (--undistorted DIR).
bool IsFijiPositionsPath(const std::filesystem::path& path);
std::string PositionsFiji(const StitchedLayout& stitched);

// --mosaic PATH before anything is read: an X3P height map needs the pixel size. After the tiles are read: it
// needs float tiles (heights in mm). InputError naming --mosaic.
void CheckMosaicPath(const std::string& path, double pixel_mm);
void CheckMosaicTiles(const std::string& path, imaging::TilePixelType type);
// The tiles fused at their positions (the undistorted tiles with a field).
imaging::Mosaic FuseStitched(const StitchedLayout& stitched, const std::vector<imaging::TileImage>& images,
                             const std::function<void(int done, int total)>& on_tile = {});
// An X3P height map in the stage frame when `path` ends in .x3p, else an image of the tiles' pixel type (0 where
// no tile reaches, for integer pixels).
void WriteMosaic(const std::string& path, imaging::Mosaic mosaic, const StitchedLayout& stitched,
                 imaging::TilePixelType type);
// --undistorted DIR: each tile without the field under its layout name, its size and pixel type (integer tiles:
// the nearest edge pixel where the raw tile does not reach, having no NaN).
void WriteUndistortedTiles(const std::filesystem::path& dir, const StitchedLayout& stitched,
                           const std::vector<imaging::TileImage>& images, imaging::TilePixelType type);

}  // namespace fvm::workflows
