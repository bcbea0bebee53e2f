// fvm focus STACK -o height.x3p: a height map from a focus stack (a CSV list of images and their z positions),
// for users who have the raw images of a focus-variation measurement rather than the instrument's height map.

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/input_error.h"
#include "core/progress.h"
#include "fvm/commands.h"
#include "imaging/io/focus_stack_io.h"
#include "imaging/focus_variation.h"
#include "imaging/height_map.h"
#include "imaging/io/height_map_image.h"
#include "imaging/io/x3p.h"
#include "imaging/tile_registration.h"  // SetImagingThreads

namespace fvm::cli {
namespace {

struct FocusArgs {
  std::string stack;
  std::string output;
  std::string measure = "laplacian";
  std::string fit = "gaussian";
  int window = 5;
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

double Median(std::vector<float> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + std::ptrdiff_t(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

void RunFocus(const FocusArgs& args) {
  imaging::FocusVariationOptions options;
  const auto measure = imaging::ParseFocusMeasure(args.measure);
  if (!measure) throw InputError("--measure: '" + args.measure + "' is not one of laplacian, tenengrad, variance");
  options.measure = *measure;
  options.peak_fit = args.fit == "parabolic" ? imaging::PeakFit::kParabolic : imaging::PeakFit::kGaussian;
  options.window = args.window;
  options.min_quality = args.min_quality;
  options.dx_mm = args.pixel_mm;
  options.Check();
  // Before any work: an output we could not write should not cost the whole stack's reading.
  KindOf(args.output);
  if (!args.quality_output.empty() && KindOf(args.quality_output) == OutputKind::kX3p) {
    throw InputError(args.quality_output + ": the quality map is written as an image (.tif, .tiff or .exr)");
  }

  const std::filesystem::path list(args.stack);
  const std::vector<imaging::FocusStackEntry> entries = imaging::ReadFocusStackList(list);
  imaging::SetImagingThreads(ThreadCount());
  imaging::FocusAccumulator accumulator(options);
  Progress progress("focus stack slices", static_cast<int>(entries.size()), ShowProgress());
  for (const imaging::FocusStackEntry& entry : entries) {
    const std::string where = list.string() + ":" + std::to_string(entry.line) + " (" + entry.file.string() + ")";
    imaging::StackImage image;
    try {
      image = imaging::ReadStackImage(entry.file);
    } catch (const InputError& e) {
      throw InputError(list.string() + ":" + std::to_string(entry.line) + ": " + e.what());
    }
    accumulator.Add(image.View(), entry.z_mm, where);
    progress.Advance();
  }
  progress.Finish();
  const imaging::FocusResult result = accumulator.Finish();
  const imaging::HeightMap& map = result.height;
  WriteMap(args.output, map);
  if (!args.quality_output.empty()) {
    imaging::HeightMap quality = map;
    quality.z_mm.assign(result.quality.begin(), result.quality.end());
    quality.source = "focus quality (peak over mean focus measure)";
    WriteMap(args.quality_output, quality);
  }

  const imaging::HeightMapStats stats = imaging::ComputeStats(map);
  std::vector<float> valid_quality;
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    if (std::isfinite(map.z_mm[i])) valid_quality.push_back(result.quality[i]);
  }
  const double median_quality = Median(result.quality);
  const double median_valid_quality = Median(valid_quality);
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
    out["median_quality"] = median_quality;
    out["median_quality_valid"] = median_valid_quality;
    out["measure"] = imaging::FocusMeasureName(options.measure);
    out["window"] = options.window;
    out["min_quality"] = options.min_quality;
    fmt::print("{}\n", out.dump(2));
    return;
  }
  fmt::print("{}\n", args.output);
  fmt::print("  stack          {} images, z {:.6f} .. {:.6f} mm\n", entries.size(), entries.front().z_mm,
             entries.back().z_mm);
  fmt::print("  measure        {}, window {} px, min quality {:g}\n", imaging::FocusMeasureName(options.measure),
             options.window, options.min_quality);
  fmt::print("  grid           {} x {} points, {:g} um pixels\n", map.size_x, map.size_y, map.dx_mm * 1e3);
  fmt::print("  valid points   {} of {} ({:.2f} %)\n", stats.valid_points, points,
             points > 0 ? 100.0 * double(stats.valid_points) / double(points) : 0.0);
  if (stats.valid_points > 0) {
    fmt::print("  z range        {:.6f} .. {:.6f} mm ({:.3f} um)\n", stats.z_min_mm, stats.z_max_mm,
               (stats.z_max_mm - stats.z_min_mm) * 1e3);
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
      "Rebuilds a height map from a focus stack: grey images of the same size taken at known z positions. "
      "Per pixel, a focus measure over a small window peaks where the surface is sharp; the peak's z, "
      "interpolated between the images, is the height. Pixels whose peak is weak (quality = peak over mean "
      "measure below --min-quality) or at the first or last image are left invalid. STACK is a CSV list "
      "'file,z_mm' (one row per image, by increasing or decreasing z; '#' comments; relative paths from the "
      "list's directory); images are 8 or 16 bit or float (TIFF, PNG, anything OpenImageIO reads).");
  sub->add_option("STACK", args->stack, "CSV list of the images: file,z_mm")->required();
  sub->add_option("-o,--output", args->output, "the height map: .x3p, or .tif/.tiff/.exr (float mm)")->required();
  sub->add_option("--measure", args->measure, "focus measure")
      ->check(CLI::IsMember({"laplacian", "tenengrad", "variance"}))
      ->default_str("laplacian");
  sub->add_option("--fit", args->fit, "sub-step peak interpolation through the best image and its neighbours")
      ->check(CLI::IsMember({"gaussian", "parabolic"}))
      ->default_str("gaussian");
  sub->add_option("--window-px", args->window, "focus window, odd number of px (3 to 51)")->check(Count(3, 51))->default_str("5");
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
                "\"z_min_mm\", \"z_max_mm\", \"median_quality\", ...}");
  sub->footer("Example: fvm focus stack.csv -o height.x3p --measure tenengrad --pixel-mm 0.00088");
  sub->callback([args] { RunFocus(*args); });
}

}  // namespace fvm::cli
