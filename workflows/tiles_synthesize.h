#pragma once
// `fvm tiles synthesize`: tile sets with a known truth for fvm stitch, written to a directory as fvm stitch reads
// them (workflows/tile_set_files.h) with truth.csv: a dense random texture ("waves"), a sparse sample on a
// drifting stage ("sparse", artefacts/simulation/sparse_tile_synthesis.h), or height maps of a known artefact
// (artefacts/simulation/height_tile_synthesis.h, with calottes.csv). For every front end.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "workflows/summary.h"

namespace fvm::workflows {

struct TilesSynthesizeOptions {
  std::string output;     // -o: the directory for the tiles, layout.csv and truth.csv
  int rows = 0, cols = 0;  // 0: 3 (waves), 5 (sparse), or as many as cover the artefact
  std::optional<int> tile_px;    // --tile-px; none: 256 (sparse: 245 x 183)
  std::optional<double> overlap;  // --overlap, a fraction; none: 0.2 (sparse: 0.06)
  double stage_sigma_px = 1.5;  // the stage error per axis (sparse: the repeatability on its step error)
  int bits = 0;                 // 8, 16 or 32 (float); 0: 16, or 32 for height tiles
  std::string artefact;         // grid6x6 or bar17: height tiles instead
  std::string texture = "waves";  // waves or sparse
  std::uint64_t seed = 1;
};

struct SynthesizedTileSet {
  std::string kind;  // "waves", "sparse" or "heights"
  std::string artefact, output;
  int width_px = 0, height_px = 0;
  double overlap = 0.0;
  double pixel_mm = 0.0;           // height tiles: the map's pixel size
  std::vector<std::string> files;  // the tiles written, in the layout's order
};

// Writes the set; throws InputError naming the option (--bits, --texture with --artefact, a texture or artefact
// that does not exist, sizes the synthesis refuses).
SynthesizedTileSet SynthesizeTileSet(const TilesSynthesizeOptions& options);

// {"kind", "tiles", "width_px", "height_px", "overlap"[, "pixel_mm", "artefact"]} and the line the command prints.
Summary Summarize(const SynthesizedTileSet& set);

}  // namespace fvm::workflows
