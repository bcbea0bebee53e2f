#pragma once
// The imaging code that needs OpenCV (calotte detection, tile registration and mosaics, focus variation), seen
// through one table of its entry points, so that the fvm executable loads OpenCV only when a command first works
// on an image. OpenCV's video module pulls dnn, calib3d, protobuf and X11 on Debian: mapping them cost every
// process about 25 ms before main, and commands that never touch an image (calibrate on centre exports, verify,
// diff, ...) should not pay that (issue 47).
//
// How it is built (imaging/CMakeLists.txt): the OpenCV files form the static library fvm_imaging_opencv, linked
// into whatever links fvm_imaging (tests, benchmarks, the Python module) and into the plugin
// libfvm_imaging_opencv.so (io/plugins/opencv_imaging.cc), which returns this table. The fvm executable links
// opencv_on_demand.cc instead: the same functions, each forwarded through the table of the plugin, loaded on the
// first call (io/plugin_loader.h). Call sites do not change.
//
// A function of these files newly called from outside them (artefacts/, workflows/, fvm/) needs a member here, its
// line in the plugin's table and its forwarder in opencv_on_demand.cc; without them the fvm executable does not
// link ("undefined reference"). The members take their types from the declarations, so a changed signature
// needs only the forwarder changed.

#include <string_view>

#include "imaging/calotte_detection.h"
#include "imaging/field_distortion.h"
#include "imaging/focus_variation.h"
#include "imaging/io/focus_stack_files.h"
#include "imaging/overlap_correspondences.h"
#include "imaging/tile_mosaic.h"
#include "imaging/tile_pair_registration.h"
#include "imaging/tile_registration.h"

namespace fvm::imaging {

// The plugin's function table (entry point "fvm_imaging_opencv_v1").
struct OpenCvImaging {
  decltype(&DetectCalottes) detect_calottes;
  decltype(&CalotteDetectionOptions::Check) check_calotte_detection_options;
  decltype(&RegistrationOptions::Check) check_registration_options;
  decltype(&RegisterPair) register_pair;
  decltype(&SolveTilePositions) solve_tile_positions;
  decltype(&RegisterTileGrid) register_tile_grid;
  decltype(&RegisterTileChain) register_tile_chain;
  decltype(&SetImagingThreads) set_imaging_threads;
  decltype(&FuseTiles) fuse_tiles;
  decltype(&MosaicToHeightMap) mosaic_to_height_map;
  decltype(&FocusMeasureName) focus_measure_name;
  decltype(&ParseFocusMeasure) parse_focus_measure;
  decltype(&FocusVariationOptions::Check) check_focus_variation_options;
  decltype(&ResolveFocusStack) resolve_focus_stack;
  decltype(&ReconstructFocusStackFiles) reconstruct_focus_stack_files;
  decltype(&AllInFocusImage) all_in_focus_image;
  decltype(&UndistortTiles) undistort_tiles;
  decltype(&UndistortTile) undistort_tile;
  decltype(&DistortTile) distort_tile;
  decltype(&CorrespondenceOptions::Check) check_correspondence_options;
  decltype(&MatchOverlap) match_overlap;
  decltype(&MatchOverlaps) match_overlaps;
  decltype(&PrepareTilesForMatching) prepare_tiles_for_matching;
  decltype(&MatchPreparedOverlaps) match_prepared_overlaps;
};

// The table, loading the plugin on first use. `action` says what needed it ("registering tiles"); when the plugin
// cannot be loaded, throws InputError "<action> needs OpenCV: libfvm_imaging_opencv.so could not be loaded (...);
// install the Debian packages ...".
const OpenCvImaging& LoadOpenCvImaging(std::string_view action);

}  // namespace fvm::imaging
