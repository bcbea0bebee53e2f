// fvm focus STACK -o height.x3p: a height map from a focus stack (a CSV list of images and their z positions, a
// directory of images or the images themselves), with its uncertainty and the all-in-focus image, for users who
// have the raw images of a focus-variation measurement rather than the instrument's height map.

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/input_error.h"
#include "core/progress.h"
#include "fvm/commands.h"
#include "imaging/io/focus_stack_files.h"
#include "imaging/io/focus_stack_io.h"
#include "imaging/focus_variation.h"
#include "imaging/height_map.h"
#include "imaging/io/height_map_image.h"
#include "imaging/io/x3p.h"
#include "fvm/summary_output.h"
#include "workflows/focus.h"

namespace fvm::cli {
namespace {

struct FocusArgs {
  std::vector<std::string> stack;
  std::string texture_output;
  std::string uncertainty_output;
  std::string output;
  std::string quality_output;
  bool json = false;
  workflows::FocusOptions options;
};

enum class OutputKind { kX3p, kImage };

OutputKind KindOf(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".x3p") return OutputKind::kX3p;
  if (ext == ".tif" || ext == ".tiff" || ext == ".exr") return OutputKind::kImage;
  throw InputError(path.string() + ": unknown output type '" + ext + "'; use .x3p, .tif, .tiff or .exr");
}

void WriteMap(const std::filesystem::path& path, const imaging::HeightMap& map) {
  if (KindOf(path) == OutputKind::kX3p) {
    imaging::WriteX3p(path, map);
  } else {
    imaging::WriteHeightMapImage(path, map);
  }
}

// An image of one value per pixel on the height map's grid (quality, uncertainty).
void WriteGridValues(const std::string& path, const imaging::HeightMap& map, const std::vector<float>& values,
                     const std::string& source) {
  imaging::HeightMap grid = map;
  grid.z_mm.assign(values.begin(), values.end());
  grid.source = source;
  WriteMap(path, grid);
}

void RunFocus(FocusArgs args) {
  args.options.Check();
  // Before any work: an output we could not write should not cost the whole stack's reading.
  KindOf(args.output);
  if (!args.quality_output.empty() && KindOf(args.quality_output) == OutputKind::kX3p) {
    throw InputError(args.quality_output + ": the quality map is written as an image (.tif, .tiff or .exr)");
  }
  if (!args.uncertainty_output.empty()) KindOf(args.uncertainty_output);

  args.options.colour = !args.texture_output.empty();
  args.options.threads = ThreadCount();
  std::vector<imaging::FocusStackEntry> stack = imaging::ResolveFocusStack(
      std::vector<std::filesystem::path>(args.stack.begin(), args.stack.end()), args.options.z_step_mm);
  Progress progress("focus stack slices", static_cast<int>(stack.size()), ShowProgress());
  const workflows::FocusSummary focus =
      workflows::ReconstructFocus(std::move(stack), args.options, [&] { progress.Advance(); });
  progress.Finish();
  const imaging::FocusResult& result = focus.read.focus;
  WriteMap(args.output, focus.map);
  if (!args.quality_output.empty()) {
    WriteGridValues(args.quality_output, focus.map, result.quality, "focus quality (peak over mean focus measure)");
  }
  if (!args.uncertainty_output.empty()) {
    WriteGridValues(args.uncertainty_output, focus.map, result.u_z_mm,
                    "focus variation: standard uncertainty u_z of each height (k = 1)");
  }
  if (!args.texture_output.empty()) {
    imaging::WriteStackImage(args.texture_output, imaging::AllInFocusImage(result, focus.read.eight_bit));
  }
  PrintSummary(workflows::Summarize(focus, args.output), args.json, {{"file", args.output, "images"}});
}

}  // namespace

void RegisterFocus(CLI::App& app) {
  auto args = std::make_shared<FocusArgs>();
  CLI::App* sub = app.add_subcommand("focus", "height map from a focus stack");
  AddDetails(sub,
      "Rebuilds a height map from a focus stack: images of the same size taken at known z positions. "
      "Per pixel, a focus measure over a window peaks where the surface is sharp; the peak's z, "
      "interpolated between the images (a parabola through the measure's -2/p power, p its fall with the blur), is "
      "the height. The window is 9 px on flats and 3 and 5 px on walls (chosen by the local slope) unless "
      "--window-px fixes it. Pixels whose peak is weak (quality = peak over mean measure below --min-quality) "
      "or at the first or last image are left invalid, not guessed. STACK is a CSV list 'file,z_mm' (one row per "
      "image, by increasing or decreasing z; '#' comments; relative paths from the list's directory), or a "
      "directory of images (by name), or the image files in focus order; without a list, z is the image's index "
      "times --z-step-mm, or the index itself (heights in slice units). Images are 8 or 16 bit or float, grey "
      "or colour (averaged to grey for the measure; TIFF, PNG, JPEG, anything OpenImageIO reads).");
  sub->add_option("STACK", args->stack, "CSV list 'file,z_mm', a directory of images, or the images in order")
      ->required();
  sub->add_option("--z-step-mm", args->options.z_step_mm,
                  "z between images named directly or in a directory (mm); without it heights are in slices. "
                  "Example: fvm focus frames/ -o h.x3p --z-step-mm 0.002")
      ->check(Within(-1e3, 1e3));
  sub->add_flag("--align", args->options.align,
                "register each image to its neighbour (enhanced correlation, affine) and resample it into the "
                "first image's frame, for a lens that breathes or a camera that shifts. Example: fvm focus "
                "frames/ -o h.tif --align --texture sharp.png");
  sub->add_flag("--keep-end-peaks", args->options.keep_end_peaks,
                "give pixels sharpest in the first or last image that image's z (u_z one step) instead of leaving "
                "them invalid, for a stack that ends on the scene's nearest and farthest parts. Example: fvm focus "
                "frames/ -o h.tif --align --keep-end-peaks");
  sub->add_option("--texture", args->texture_output,
                  "also write the all-in-focus image (.png, .tif, .jpg; colour when the images are). "
                  "Example: --texture sharp.png");
  sub->add_option("--uncertainty", args->uncertainty_output,
                  "also write the standard uncertainty u_z of each height (k = 1; .x3p, .tif, .tiff, .exr). "
                  "Example: --uncertainty u_z.tif");
  sub->add_option("-o,--output", args->output, "the height map: .x3p, or .tif/.tiff/.exr (float mm)")->required();
  sub->add_option("--measure", args->options.measure, "focus measure")
      ->check(CLI::IsMember({"laplacian", "tenengrad", "variance"}))
      ->default_str("laplacian");
  sub->add_option("--fit", args->options.fit,
                  "sub-step peak interpolation: power (a parabola through the measure's -2/p power, up to 2 "
                  "images either side), gaussian (through its log) or parabolic (through the measure), both "
                  "through the best image and its neighbours")
      ->check(CLI::IsMember({"power", "gaussian", "parabolic"}))
      ->default_str("power");
  sub->add_option("--window-px", args->options.window_px, "a fixed focus window, odd number of px (3 to 51); default adaptive")
      ->check(Count(3, 51));
  AddHiddenAlias(sub, "--window", args->options.window_px, "--window-px");
  sub->add_option("--min-quality", args->options.min_quality, "peak over mean focus measure below this: invalid")
      ->check(Within(0.0, 1e6))
      ->default_str("2");
  sub->add_option("--pixel-mm", args->options.pixel_mm, "pixel size on the object in mm")
      ->check(Within(kPixelMm))
      ->default_str("0.001");
  sub->add_option("--quality", args->quality_output, "also write the quality map (.tif, .tiff or .exr)");
  sub->add_flag("--json", args->json,
                "print one JSON document {\"size_x\", \"size_y\", \"dx_mm\", \"dy_mm\", \"valid_points\", "
                "\"z_min_mm\", \"z_max_mm\", \"z_unit\", \"u_z_median\", \"median_quality\", ...}");
  sub->footer("Examples:\n  fvm focus stack.csv -o height.x3p --uncertainty u_z.tif --texture sharp.png --pixel-mm 0.00088\n"
              "  fvm focus pcb/*.jpg -o height.tif --align --texture sharp.png");
  sub->callback([args] { RunFocus(*args); });
}

}  // namespace fvm::cli
