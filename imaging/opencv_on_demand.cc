// The imaging functions that need OpenCV, as the fvm executable links them: each forwards to the plugin
// libfvm_imaging_opencv.so, loaded on the first call (imaging/opencv_imaging.h says why and how).

#include <string>

#include "imaging/io/plugin_loader.h"
#include "imaging/opencv_imaging.h"

namespace fvm::imaging {

const OpenCvImaging& LoadOpenCvImaging(std::string_view action) {
  static constexpr PluginSpec kPlugin{"libfvm_imaging_opencv.so", "fvm_imaging_opencv_v1", "OpenCV",
                                      "libopencv-video406"};
  return *static_cast<const OpenCvImaging*>(LoadPlugin(kPlugin, action));
}

CalotteDetection DetectCalottes(const HeightMap& map, const CalotteDetectionOptions& options) {
  return LoadOpenCvImaging("finding calottes").detect_calottes(map, options);
}

void CalotteDetectionOptions::Check() const {
  (this->*LoadOpenCvImaging("checking the calotte search").check_calotte_detection_options)();
}

void RegistrationOptions::Check() const {
  (this->*LoadOpenCvImaging("checking the registration options").check_registration_options)();
}

PairRegistration RegisterPair(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                              const RegistrationOptions& options) {
  return LoadOpenCvImaging("registering tiles").register_pair(a, b, nominal_px, options);
}

TilePositions SolveTilePositions(const std::vector<Eigen::Vector2d>& nominal_px,
                                 const std::vector<PairRegistration>& pairs, double stage_sigma_px,
                                 const Eigen::Vector2d& unregistered_sigma_px) {
  return LoadOpenCvImaging("placing tiles").solve_tile_positions(nominal_px, pairs, stage_sigma_px,
                                                                 unregistered_sigma_px);
}

RegistrationResult RegisterTileGrid(const std::vector<TileImage>& images, const std::vector<GridTile>& tiles,
                                    const RegistrationOptions& options,
                                    const std::function<void(int done, int total)>& on_pair_registered) {
  return LoadOpenCvImaging("registering tiles").register_tile_grid(images, tiles, options, on_pair_registered);
}

ChainRegistration RegisterTileChain(const std::vector<TileImage>& images, const std::vector<Eigen::Vector2d>& nominal_px,
                                    const RegistrationOptions& options,
                                    const std::function<void(int done, int total)>& on_pair_registered) {
  return LoadOpenCvImaging("registering tiles").register_tile_chain(images, nominal_px, options, on_pair_registered);
}

void SetImagingThreads(int threads) { LoadOpenCvImaging("setting the image threads").set_imaging_threads(threads); }

Mosaic FuseTiles(const std::vector<TileImage>& tiles, const std::vector<Eigen::Vector2d>& positions_px,
                 const std::function<void(int done, int total)>& on_tile_fused) {
  return LoadOpenCvImaging("fusing tiles").fuse_tiles(tiles, positions_px, on_tile_fused);
}

HeightMap MosaicToHeightMap(const Mosaic& mosaic, int tile_width, int tile_height, double pixel_mm,
                            const Eigen::Vector2d& first_centre_mm) {
  return LoadOpenCvImaging("fusing tiles").mosaic_to_height_map(mosaic, tile_width, tile_height, pixel_mm,
                                                                first_centre_mm);
}

std::string FocusMeasureName(FocusMeasure measure) {
  return LoadOpenCvImaging("focus variation").focus_measure_name(measure);
}

std::optional<FocusMeasure> ParseFocusMeasure(std::string_view name) {
  return LoadOpenCvImaging("focus variation").parse_focus_measure(name);
}

void FocusVariationOptions::Check() const {
  (this->*LoadOpenCvImaging("focus variation").check_focus_variation_options)();
}

std::vector<FocusStackEntry> ResolveFocusStack(const std::vector<std::filesystem::path>& inputs,
                                               std::optional<double> step_mm) {
  return LoadOpenCvImaging("reading a focus stack").resolve_focus_stack(inputs, step_mm);
}

FocusStackFilesResult ReconstructFocusStackFiles(const std::vector<FocusStackEntry>& entries,
                                                 const FocusStackFilesOptions& options,
                                                 const std::function<void()>& on_image) {
  return LoadOpenCvImaging("reading a focus stack").reconstruct_focus_stack_files(entries, options, on_image);
}

StackImage AllInFocusImage(const FocusResult& result, bool eight_bit) {
  return LoadOpenCvImaging("writing the all-in-focus image").all_in_focus_image(result, eight_bit);
}

std::vector<TileImage> UndistortTiles(const std::vector<TileImage>& raw, const FieldDistortion& field,
                                      bool outside_nan) {
  return LoadOpenCvImaging("resampling tiles without the field distortion").undistort_tiles(raw, field, outside_nan);
}

TileImage UndistortTile(const TileImage& raw, const FieldDistortion& field, bool outside_nan) {
  return LoadOpenCvImaging("resampling tiles without the field distortion").undistort_tile(raw, field, outside_nan);
}

TileImage DistortTile(const TileImage& ideal_with_margin, int margin_px, const FieldDistortion& field) {
  return LoadOpenCvImaging("rendering tiles through a field distortion").distort_tile(ideal_with_margin, margin_px,
                                                                                        field);
}

void CorrespondenceOptions::Check() const {
  (this->*LoadOpenCvImaging("checking the overlap matching options").check_correspondence_options)();
}

PairCorrespondences MatchOverlap(const TileImage& a, const TileImage& b, int a_index, int b_index,
                                 const Eigen::Vector2d& offset_px, const FieldDistortion& guess,
                                 const CorrespondenceOptions& options) {
  return LoadOpenCvImaging("matching overlaps").match_overlap(a, b, a_index, b_index, offset_px, guess, options);
}

std::vector<PairCorrespondences> MatchOverlaps(const std::vector<TileImage>& images,
                                               const std::vector<OverlapToMatch>& overlaps,
                                               const FieldDistortion& guess, const CorrespondenceOptions& options) {
  return LoadOpenCvImaging("matching overlaps").match_overlaps(images, overlaps, guess, options);
}

PreparedTiles PrepareTilesForMatching(const std::vector<TileImage>& images, const CorrespondenceOptions& options) {
  return LoadOpenCvImaging("matching overlaps").prepare_tiles_for_matching(images, options);
}

std::vector<PairCorrespondences> MatchPreparedOverlaps(const PreparedTiles& tiles,
                                                       const std::vector<OverlapToMatch>& overlaps,
                                                       const FieldDistortion& guess,
                                                       const CorrespondenceOptions& options) {
  return LoadOpenCvImaging("matching overlaps").match_prepared_overlaps(tiles, overlaps, guess, options);
}

}  // namespace fvm::imaging
