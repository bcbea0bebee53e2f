#pragma once
// A batch of raw exports: per placement one stitched and one stitching-free surface as the instrument exports them
// (<placement>.stitched.x3p / <placement>.free.x3p; also .al3d, .sdf, .tif/.tiff), turned into the centre exports
// of a CSV batch (artefacts/io/batch.h) by the calotte search and sphere fits of `fvm fit`.
//
// Numbering. The stitched surface is numbered by the artefact's nominal layout (imaging/calotte_numbering.h). A bar
// measured along y fits turned by +90 and -90 degrees equally; then the numbering expecting a turn 45 degrees on
// is taken: which of the two labels the calottes get is immaterial, as ids only pair the two exports of one
// placement (the bar is uncalibrated: no id is compared across placements). The stitching-free surface is then
// numbered expecting the stitched surface's rotation (both see the part through the same stage within tens of
// microradians), so the two numberings agree or fail visibly. They must then hold the same calottes, and no
// calotte may lie further from its partner than a quarter of the artefact's smallest spacing: the stitched
// export lies at its first tile's stage reading (docs/concepts/stitched-frame.md), so the two differ by the stage
// error, a fraction of that. Otherwise the batch is refused with the
// calotte ids named. Both surfaces must therefore carry their stage position (X3P axes' offsets).
//
// Folders of stitching-free tiles (one file per calotte with its stage position) are not read yet: one surface per
// export.

#include <filesystem>
#include <string>
#include <vector>

#include "artefacts/geometry/artefact.h"
#include "artefacts/io/batch.h"
#include "artefacts/io/centre_export.h"
#include "imaging/calotte_detection.h"

namespace fvm::artefacts {

struct RawExportBatchOptions {
  std::string artefact = "bar17";  // a name KnownArtefact knows: the calottes' layout, diameter window
  double expected_rotation_rad = 0.0;  // how the artefact lies in the stitched surfaces (calotte 1 at lowest x)
};

// One export's search: what was read and what was found.
struct RawExportFit {
  std::string placement;
  std::filesystem::path file;
  bool stitched = true;
  CentreExport centres;      // as `fvm fit --artefact A -o` writes it
  std::size_t rejected = 0;  // depressions that were not taken as calottes
};

struct RawExportBatch {
  Batch batch;                      // as ReadBatch returns it for the centre exports below (batch.json applied)
  std::vector<RawExportFit> fits;   // stitched then free, placement by placement
};

// The surface extensions a raw batch may hold, with the dot: .x3p .al3d .sdf .tif .tiff and the instruments' exports
// .plu .dat (Zygo MetroPro) .opd .sur .nms .tmd
const std::vector<std::string>& RawExportExtensions();

// True when `dir` holds no <placement>.stitched.csv but at least one <placement>.stitched.<surface>: the batch is
// to be read by ReadRawExportBatch.
bool HoldsRawExports(const std::filesystem::path& dir);

// Throws InputError naming the file on: a placement with only one of its exports, two surfaces for one export
// (a.stitched.x3p and a.stitched.al3d), an unreadable surface, no calotte found, an ambiguous layout, and
// numberings that disagree between the two exports of a placement (naming the calotte ids).
RawExportBatch ReadRawExportBatch(const std::filesystem::path& dir, const RawExportBatchOptions& options = {});

// Writes the centre exports the search made as a CSV batch in `dir` (<placement>.stitched.csv / .free.csv with
// radius and form deviation, and batch.json when the raw batch had one), file by file atomically: `fvm calibrate
// DIR` then gives the same calibration without searching again. Throws InputError when `dir` is the raw batch.
void WriteRawExportCentres(const std::filesystem::path& dir, const RawExportBatch& raw);

// The calottes found, as records of a centre export (id, centre, radius, form deviation, converged) in `out`, with
// a comment for each sphere fit that did not converge. What `fvm fit -o` writes.
void AddFoundCentres(const imaging::CalotteDetection& detection, CentreExport& out);

// The calotte search of `fvm fit --artefact NAME`: the artefact's calottes are all alike, so a window around
// their diameter keeps other dents out (openings of ball-nose calottes can be much narrower than the ball, hence
// the wide lower bound).
imaging::CalotteDetectionOptions CalotteSearchFor(const Artefact& artefact);

}  // namespace fvm::artefacts
