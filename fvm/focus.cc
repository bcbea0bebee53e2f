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
#include <nlohmann/json.hpp>
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
#include "workflows/focus.h"

namespace fvm::cli {
namespace {

struct FocusArgs {
  std::vector<std::string> stack;
  std::optional<double> z_step_mm;
  bool align = false;
  bool keep_end_peaks = false;
  std::string texture_output;
  std::string uncertainty_output;
  std::string output;
  std::string measure = "laplacian";
  std::string fit = "power";
  int window = 0;  // 0: adaptive
  double min_quality = 2.0;
  double pixel_mm = 0.001;
  std::string quality_output;
  bool json = false;
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

void RunFocus(const FocusArgs& args) {
  imaging::FocusVariationOptions options;
  const auto measure = imaging::ParseFocusMeasure(args.measure);
  if (!measure) throw InputError("--measure: '" + args.measure + "' is not one of laplacian, tenengrad, variance");
  options.measure = *measure;
  options.peak_fit = args.fit == "parabolic" ? imaging::PeakFit::kParabolic
                     : args.fit == "gaussian"  ? imaging::PeakFit::kGaussian
                                               : imaging::PeakFit::kPower;
  options.adaptive_window = args.window == 0;
  if (args.window != 0) options.window = args.window;
  options.min_quality = args.min_quality;
  options.keep_end_peaks = args.keep_end_peaks;
  options.dx_mm = args.pixel_mm;
  options.Check();
  // Before any work: an output we could not write should not cost the whole stack's reading.
  KindOf(args.output);
  if (!args.quality_output.empty() && KindOf(args.quality_output) == OutputKind::kX3p) {
    throw InputError(args.quality_output + ": the quality map is written as an image (.tif, .tiff or .exr)");
  }
  if (!args.uncertainty_output.empty()) KindOf(args.uncertainty_output);

  const workflows::FocusOptions job{options, args.z_step_mm, args.align, !args.texture_output.empty(), ThreadCount()};
  std::vector<imaging::FocusStackEntry> stack =
      imaging::ResolveFocusStack(std::vector<std::filesystem::path>(args.stack.begin(), args.stack.end()), args.z_step_mm);
  Progress progress("focus stack slices", static_cast<int>(stack.size()), ShowProgress());
  const workflows::FocusSummary summary = workflows::ReconstructFocus(std::move(stack), job, [&] { progress.Advance(); });
  progress.Finish();
  const std::vector<imaging::FocusStackEntry>& entries = summary.entries;
  const imaging::FocusStackFilesResult& read = summary.read;
  const imaging::FocusResult& result = read.focus;
  const imaging::HeightMap& map = summary.map;
  const bool slice_units = summary.slice_units;
  WriteMap(args.output, map);
  if (!args.quality_output.empty()) {
    imaging::HeightMap quality = map;
    quality.z_mm.assign(result.quality.begin(), result.quality.end());
    quality.source = "focus quality (peak over mean focus measure)";
    WriteMap(args.quality_output, quality);
  }
  if (!args.uncertainty_output.empty()) {
    imaging::HeightMap u = map;
    u.z_mm.assign(result.u_z_mm.begin(), result.u_z_mm.end());
    u.source = "focus variation: standard uncertainty u_z of each height (k = 1)";
    WriteMap(args.uncertainty_output, u);
  }
  if (!args.texture_output.empty()) {
    imaging::WriteStackImage(args.texture_output, imaging::AllInFocusImage(result, read.eight_bit));
  }

  const imaging::HeightMapStats& stats = summary.stats;
  const double median_quality = summary.median_quality;
  const double median_valid_quality = summary.median_valid_quality;
  const double median_u = summary.median_u;
  const char* unit = slice_units ? "slice" : "mm";
  const std::size_t points = map.z_mm.size();
  if (args.json) {
    nlohmann::ordered_json out;
    out["file"] = args.output;
    out["images"] = entries.size();
    out["size_x"] = map.size_x;
    out["size_y"] = map.size_y;
    out["dx_mm"] = map.dx_mm;
    out["dy_mm"] = map.dy_mm;
    out["valid_points"] = stats.valid_points;
    out["z_min_mm"] = stats.valid_points > 0 ? nlohmann::ordered_json(stats.z_min_mm) : nlohmann::ordered_json();
    out["z_max_mm"] = stats.valid_points > 0 ? nlohmann::ordered_json(stats.z_max_mm) : nlohmann::ordered_json();
    out["z_unit"] = unit;
    out["u_z_median"] = stats.valid_points > 0 ? nlohmann::ordered_json(median_u) : nlohmann::ordered_json();
    out["aligned"] = args.align;
    out["unregistered_images"] = read.unregistered;
    out["median_quality"] = median_quality;
    out["median_quality_valid"] = median_valid_quality;
    out["measure"] = imaging::FocusMeasureName(options.measure);
    out["window"] = options.adaptive_window ? nlohmann::ordered_json("adaptive") : nlohmann::ordered_json(options.window);
    out["min_quality"] = options.min_quality;
    fmt::print("{}\n", out.dump(2));
    return;
  }
  fmt::print("{}\n", args.output);
  fmt::print("  stack          {} images, z {:.6f} .. {:.6f} {}{}\n", entries.size(), entries.front().z_mm,
             entries.back().z_mm, unit, args.align ? ", aligned to the first" : "");
  fmt::print("  measure        {}, window {}, min quality {:g}\n", imaging::FocusMeasureName(options.measure),
             options.adaptive_window ? std::string("adaptive 5/9 px") : fmt::format("{} px", options.window),
             options.min_quality);
  if (read.unregistered > 0) {
    fmt::print("  alignment      {} image(s) shared no sharp texture with their neighbour: kept its place\n",
               read.unregistered);
  }
  fmt::print("  grid           {} x {} points, {:g} um pixels\n", map.size_x, map.size_y, map.dx_mm * 1e3);
  fmt::print("  valid points   {} of {} ({:.2f} %)\n", stats.valid_points, points,
             points > 0 ? 100.0 * double(stats.valid_points) / double(points) : 0.0);
  if (stats.valid_points > 0) {
    if (slice_units) {
      fmt::print("  z range        {:.3f} .. {:.3f} slices\n", stats.z_min_mm, stats.z_max_mm);
      fmt::print("  u_z median     {:.3f} slices\n", median_u);
    } else {
      fmt::print("  z range        {:.6f} .. {:.6f} mm ({:.3f} um)\n", stats.z_min_mm, stats.z_max_mm,
                 (stats.z_max_mm - stats.z_min_mm) * 1e3);
      fmt::print("  u_z median     {:.4f} um\n", median_u * 1e3);
    }
  } else {
    fmt::print("  no valid point: no pixel has a clear focus peak inside the stack\n");
  }
  fmt::print("  median quality {:.3g} (valid points {:.3g})\n", median_quality, median_valid_quality);
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
  sub->add_option("--z-step-mm", args->z_step_mm,
                  "z between images named directly or in a directory (mm); without it heights are in slices. "
                  "Example: fvm focus frames/ -o h.x3p --z-step-mm 0.002")
      ->check(Within(-1e3, 1e3));
  sub->add_flag("--align", args->align,
                "register each image to its neighbour (enhanced correlation, affine) and resample it into the "
                "first image's frame, for a lens that breathes or a camera that shifts. Example: fvm focus "
                "frames/ -o h.tif --align --texture sharp.png");
  sub->add_flag("--keep-end-peaks", args->keep_end_peaks,
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
  sub->add_option("--measure", args->measure, "focus measure")
      ->check(CLI::IsMember({"laplacian", "tenengrad", "variance"}))
      ->default_str("laplacian");
  sub->add_option("--fit", args->fit,
                  "sub-step peak interpolation: power (a parabola through the measure's -2/p power, up to 2 "
                  "images either side), gaussian (through its log) or parabolic (through the measure), both "
                  "through the best image and its neighbours")
      ->check(CLI::IsMember({"power", "gaussian", "parabolic"}))
      ->default_str("power");
  sub->add_option("--window-px", args->window, "a fixed focus window, odd number of px (3 to 51); default adaptive")
      ->check(Count(3, 51));
  AddHiddenAlias(sub, "--window", args->window, "--window-px");
  sub->add_option("--min-quality", args->min_quality, "peak over mean focus measure below this: invalid")
      ->check(Within(0.0, 1e6))
      ->default_str("2");
  sub->add_option("--pixel-mm", args->pixel_mm, "pixel size on the object in mm")
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
