// The plugin libfvm_imaging_opencv.so: the imaging code that needs OpenCV, linked in whole (fvm_imaging_opencv),
// behind its table (imaging/opencv_imaging.h).

#include "imaging/opencv_imaging.h"

namespace fvm::imaging {
namespace {

constexpr OpenCvImaging kOpenCvImaging{
    &DetectCalottes,
    &CalotteDetectionOptions::Check,
    &RegistrationOptions::Check,
    &RegisterPair,
    &SolveTilePositions,
    &RegisterTileGrid,
    &RegisterTileChain,
    &SetImagingThreads,
    &FuseTiles,
    &MosaicToHeightMap,
    &FocusMeasureName,
    &ParseFocusMeasure,
    &FocusVariationOptions::Check,
    &ResolveFocusStack,
    &ReconstructFocusStackFiles,
    &AllInFocusImage,
    &UndistortTiles,
    &UndistortTile,
    &DistortTile,
    &CorrespondenceOptions::Check,
    &MatchOverlap,
    &MatchOverlaps,
    &PrepareTilesForMatching,
    &MatchPreparedOverlaps,
};

}  // namespace
}  // namespace fvm::imaging

extern "C" __attribute__((visibility("default"))) const void* fvm_imaging_opencv_v1() {
  return &fvm::imaging::kOpenCvImaging;
}
