// fvm stitch: register the tiles of a layout (imaging/tile_registration.h) and write their positions.

#include <fmt/core.h>
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <Eigen/LU>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "core/file_io.h"
#include "core/input_error.h"
#include "core/progress.h"
#include "fvm/commands.h"
#include "fvm/distortion_options.h"
#include "imaging/io/tile_image.h"
#include "imaging/io/tile_layout.h"
#include "imaging/tile_mosaic.h"
#include "imaging/io/x3p.h"
#include "imaging/overlap_correlation.h"
#include "imaging/tile_plan.h"
#include "imaging/tile_registration.h"
#include "workflows/field_distortion_file.h"
#include "workflows/stitch.h"
#include "workflows/stitch_distortion.h"

namespace fvm::cli {
namespace {

struct StitchArgs {
  std::string layout;
  std::string overlap;
  std::string output;
  std::string mosaic;
  double pixel_mm = 0.0;
  double min_quality = imaging::RegistrationOptions{}.min_quality;
  double stage_sigma_px = imaging::RegistrationOptions{}.stage_sigma_px;
  bool json = false;
  DistortionArgs distortion;
};

void RunStitch(const StitchArgs& args) {
  const double overlap = imaging::ParseOverlap(args.overlap, "--overlap");
  if (args.pixel_mm < 0.0 || !std::isfinite(args.pixel_mm)) {
    throw InputError(fmt::format("--pixel-mm {}: give the pixel size in mm, e.g. 0.000875", args.pixel_mm));
  }
  imaging::RegistrationOptions options;
  options.min_quality = args.min_quality;
  if (!(options.min_quality >= -1.0 && options.min_quality <= 1.0)) {
    throw InputError("--min-quality: give a correlation in [-1, 1], e.g. 0.5");
  }
  options.stage_sigma_px = args.stage_sigma_px;
  if (!(options.stage_sigma_px > 0.0) || !std::isfinite(options.stage_sigma_px)) {
    throw InputError("--stage-sigma-px: give the stage's positioning error over the grid in pixels, e.g. 2");
  }
  const bool height_map = std::filesystem::path(args.mosaic).extension() == ".x3p";
  if (height_map && !(args.pixel_mm > 0.0)) {
    throw InputError("--mosaic " + args.mosaic + ": an X3P height map needs the pixel size; give --pixel-mm");
  }
  args.distortion.Check();
  const std::optional<imaging::FieldDistortion> known_field = args.distortion.Known();
  const imaging::TileLayout layout = imaging::ReadTileLayout(args.layout);
  imaging::CheckLayoutComplete(layout);
  const std::filesystem::path dir = std::filesystem::path(args.layout).parent_path();

  imaging::TilePixelType pixel_type = imaging::TilePixelType::kFloat;
  const std::vector<imaging::TileImage> images = imaging::ReadLayoutImages(layout, dir, &pixel_type);
  if (height_map && pixel_type != imaging::TilePixelType::kFloat) {
    throw InputError(fmt::format("--mosaic {}: the tiles hold {}-bit counts, not heights; an X3P height map needs "
                                 "float tiles in mm (or write the mosaic as .tif)",
                                 args.mosaic, pixel_type == imaging::TilePixelType::kUint8 ? 8 : 16));
  }
  const double width = static_cast<double>(images.front().cols());
  const double height = static_cast<double>(images.front().rows());
  workflows::StitchOptions job{overlap, args.pixel_mm, options, ThreadCount()};
  bool from_stage = false;
  Progress pair_progress("registering pairs",
                         workflows::CountGridPairs(workflows::NominalGrid(layout, static_cast<int>(width),
                                                                          static_cast<int>(height), job, &from_stage)),
                         ShowProgress());
  const workflows::StitchResult stitched =
      workflows::StitchTiles(layout, images, job, [&](int, int) { pair_progress.Advance(); });
  pair_progress.Finish();
  const imaging::RegistrationResult& result = stitched.registration;
  const Eigen::Vector2d& origin = stitched.origin_mm;
  // With a field: the undistorted tiles' positions, their u with the field's, and the mosaic of undistorted tiles.
  std::optional<workflows::StitchDistortionResult> field;
  if (args.distortion.Requested()) {
    workflows::StitchDistortionOptions distortion_options;
    distortion_options.order = args.distortion.Order();
    distortion_options.known = known_field;
    try {
      field = workflows::StitchWithoutDistortion(stitched, images, distortion_options);
    } catch (const imaging::FieldDistortionUndeterminable& e) {
      throw InputError(fmt::format("--distortion, {}: {}", args.layout, e.what()));
    }
    if (!args.distortion.save.empty()) workflows::WriteFieldDistortion(args.distortion.save, field->fit.field, args.pixel_mm);
    if (!args.distortion.undistorted_dir.empty()) {
      // Integer tiles have no NaN: where the raw tile does not reach, the nearest edge pixel.
      const std::vector<imaging::TileImage> written =
          pixel_type == imaging::TilePixelType::kFloat ? field->undistorted
                                                       : imaging::UndistortTiles(images, field->fit.field, false);
      for (size_t i = 0; i < layout.tiles.size(); ++i) {
        const std::filesystem::path out = std::filesystem::path(args.distortion.undistorted_dir) / layout.tiles[i].file;
        std::filesystem::create_directories(out.parent_path());
        imaging::WriteTileImage(out, written[i], pixel_type);
      }
    }
  }
  const std::vector<Eigen::Vector2d>& positions = field ? field->fit.positions_px : result.positions.positions_px;
  const std::vector<Eigen::Vector2d>& sigmas = field ? field->sigma_px : result.positions.sigma_px;

  std::string csv = args.pixel_mm > 0.0 ? "file,x,y,x_mm,y_mm,registered,u_x,u_y\n" : "file,x,y,registered,u_x,u_y\n";
  for (size_t i = 0; i < layout.tiles.size(); ++i) {
    const Eigen::Vector2d& p = positions[i];
    csv += fmt::format("{},{:.4f},{:.4f}", layout.tiles[i].file, p.x(), p.y());
    if (args.pixel_mm > 0.0) {
      csv += fmt::format(",{:.6f},{:.6f}", origin.x() + p.x() * args.pixel_mm, origin.y() - p.y() * args.pixel_mm);
    }
    const Eigen::Vector2d& u = sigmas[i];
    csv += fmt::format(",{},{:.4f},{:.4f}\n", result.positions.registered[i] ? 1 : 0, u.x(), u.y());
  }
  WriteFileAtomically(args.output, csv);
  if (!args.mosaic.empty()) {
    Progress tile_progress("fusing tiles", static_cast<int>(images.size()), ShowProgress());
    imaging::Mosaic mosaic =
        imaging::FuseTiles(field ? field->undistorted : images, positions, [&](int, int) { tile_progress.Advance(); });
    tile_progress.Finish();
    if (height_map) {
      imaging::WriteX3p(args.mosaic, imaging::MosaicToHeightMap(mosaic, static_cast<int>(width),
                                                                static_cast<int>(height), args.pixel_mm, origin));
    } else {
      // Integer pixels have no NaN: where no tile reaches is 0.
      if (pixel_type != imaging::TilePixelType::kFloat) mosaic.image = mosaic.image.unaryExpr([](float v) {
        return std::isnan(v) ? 0.0f : v;
      });
      imaging::WriteTileImage(args.mosaic, mosaic.image, pixel_type);
    }
  }

  // What the loops overruled, and a run that leaves a quarter of its pairs unresolved, go to stderr whatever the
  // output: a script reading --json sees them there too.
  for (const auto& text : stitched.overruled) fmt::print(stderr, "fvm stitch: overruled {}\n", text);
  if (stitched.mostly_unresolved) fmt::print(stderr, "fvm stitch: warning: {}\n", stitched.UnresolvedWarning());
  const int accepted = stitched.accepted, ambiguous = stitched.ambiguous;
  const std::vector<std::string>& fallback = stitched.at_stage_position;
  const std::vector<std::string>& stage_bound = stitched.stage_along_one_axis;
  const std::vector<imaging::PairOverlapCorrelation>& overlap_ncc = stitched.overlap_ncc;
  const int ncc_count = stitched.ncc_pairs;
  const auto ncc_json = [](double v) { return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr); };
  if (args.json) {
    nlohmann::ordered_json out;
    out["tiles"] = layout.tiles.size();
    out["size_px"] = {images.front().cols(), images.front().rows()};
    out["nominal"] = from_stage ? "stage" : "grid";
    out["pairs_accepted"] = accepted;
    out["pairs_ambiguous"] = ambiguous;
    out["mean_overlap_ncc"] = ncc_count > 0 ? nlohmann::ordered_json(stitched.mean_overlap_ncc) : nlohmann::ordered_json(nullptr);
    out["pairs_unresolved"] = stitched.unresolved;
    out["unresolved_warning"] =
        stitched.mostly_unresolved ? nlohmann::ordered_json(stitched.UnresolvedWarning()) : nlohmann::ordered_json(nullptr);
    out["overruled"] = nlohmann::ordered_json::array();
    for (const auto& o : result.loops.overruled) {
      const imaging::PairRegistration& pair = result.pairs[static_cast<size_t>(o.pair)];
      out["overruled"].push_back({{"a", layout.tiles[static_cast<size_t>(pair.a)].file},
                                  {"b", layout.tiles[static_cast<size_t>(pair.b)].file},
                                  {"registered_px", {o.registered_px.x(), o.registered_px.y()}},
                                  {"predicted_px", {o.predicted_px.x(), o.predicted_px.y()}},
                                  {"misclosure_sigma", o.misclosure_sigma},
                                  {"replaced", o.replaced}});
    }
    out["loop_birge_ratio"] = result.loops.birge_ratio;
    out["loop_dof"] = result.loops.dof;
    out["stage_fallback"] = fallback;
    out["stage_along_one_axis"] = stage_bound;
    if (field) {
      out["distortion"] = DistortionJson(field->fit, field->identified, args.pixel_mm);
      out["distortion"]["overlap_ncc_before"] = ncc_json(field->mean_overlap_ncc_before);
      out["distortion"]["overlap_ncc_after"] = ncc_json(field->mean_overlap_ncc_after);
    }
    const imaging::TileGridSteps& model = result.stage;
    const auto component = [&](const Eigen::Vector2d& v, int k, int index) {
      return model.estimated[static_cast<size_t>(index)] ? nlohmann::ordered_json(v(k)) : nlohmann::ordered_json(nullptr);
    };
    out["stage_model"] = {
        {"east_step_px", component(model.east_px, 0, 0)},
        {"east_drift_px", component(model.east_px, 1, 1)},
        {"south_step_px", component(model.south_px, 1, 3)},
        {"south_drift_px", component(model.south_px, 0, 2)},
        {"nominal_east_px", {model.nominal_east_px.x(), model.nominal_east_px.y()}},
        {"nominal_south_px", {model.nominal_south_px.x(), model.nominal_south_px.y()}},
        {"repeatability_px",
         {model.repeatability_px.x() > 0.0 ? nlohmann::ordered_json(model.repeatability_px.x()) : nullptr,
          model.repeatability_px.y() > 0.0 ? nlohmann::ordered_json(model.repeatability_px.y()) : nullptr}},
        {"east_pairs", model.east_pairs},
        {"south_pairs", model.south_pairs},
        {"prior_sigma_px", result.stage_sigma_px},
        {"pairs_searched_again", result.pairs_searched_again}};
    out["pairs"] = nlohmann::ordered_json::array();
    for (size_t k = 0; k < result.pairs.size(); ++k) {
      const imaging::PairRegistration& pair = result.pairs[k];
      const Eigen::Vector2d d = pair.offset_px - pair.nominal_px;
      // Standard uncertainty per axis where the pair determines both; null along an axis it leaves to the stage.
      nlohmann::ordered_json sigma = {nullptr, nullptr};
      if (pair.accepted && std::abs(pair.information.determinant()) > 0.0) {
        const Eigen::Matrix2d covariance = pair.information.inverse();
        sigma = {std::sqrt(covariance(0, 0)), std::sqrt(covariance(1, 1))};
      }
      nlohmann::ordered_json candidates = nlohmann::ordered_json::array();
      for (const auto& c : pair.candidates) {
        candidates.push_back({{"dx_px", c.offset_px.x() - pair.nominal_px.x()},
                              {"dy_px", c.offset_px.y() - pair.nominal_px.y()},
                              {"peak", c.peak},
                              {"ncc", c.ncc},
                              {"overlap_px", c.overlap_px}});
      }
      out["pairs"].push_back({{"a", layout.tiles[static_cast<size_t>(pair.a)].file},
                              {"b", layout.tiles[static_cast<size_t>(pair.b)].file},
                              {"dx_px", pair.accepted ? nlohmann::ordered_json(d.x()) : nullptr},
                              {"dy_px", pair.accepted ? nlohmann::ordered_json(d.y()) : nullptr},
                              {"sigma_px", sigma},
                              {"quality", pair.quality},
                              {"accepted", pair.accepted},
                              {"overlap_ncc", ncc_json(overlap_ncc[k].correlation.ncc)},
                              {"searched", pair.searched},
                              {"ambiguous", pair.ambiguous},
                              {"unmoved", pair.unmoved},
                              {"search_px", {pair.search_px.x(), pair.search_px.y()}},
                              {"candidates", candidates},
                              {"rejection", pair.accepted ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(pair.rejection)}});
    }
    fmt::print("{}\n", out.dump(2));
    return;
  }
  fmt::print("{} tiles of {} x {} px, {} pairs, {} accepted (quality >= {}); nominal positions from the {}\n",
             layout.tiles.size(), images.front().cols(), images.front().rows(), result.pairs.size(), accepted,
             options.min_quality, from_stage ? "stage" : "grid and overlap");
  {
    const imaging::TileGridSteps& model = result.stage;
    if (!model.Any()) {
      fmt::print("  stage model: not estimated ({} registered pairs; it needs {} per direction): the nominal "
                 "positions stand\n",
                 accepted, imaging::TileGridSteps::kMinPairs);
    } else {
      const auto value = [&](const Eigen::Vector2d& v, int k, int index) {
        return model.estimated[static_cast<size_t>(index)] ? fmt::format("{:+.2f}", v(k)) : std::string("nominal");
      };
      const auto repeat = [](double r) { return r > 0.0 ? fmt::format("{:.2f}", r) : std::string("unknown"); };
      fmt::print("  stage model from {} east and {} south pairs: column step {} px (nominal {:.2f}), drift {} px "
                 "per column; row step {} px (nominal {:.2f}), drift {} px per row; repeatability {} x, {} y px; "
                 "{} pairs searched again within its tolerance\n",
                 model.east_pairs, model.south_pairs, value(model.east_px, 0, 0), model.nominal_east_px.x(),
                 value(model.east_px, 1, 1), value(model.south_px, 1, 3), model.nominal_south_px.y(),
                 value(model.south_px, 0, 2), repeat(model.repeatability_px.x()),
                 repeat(model.repeatability_px.y()), result.pairs_searched_again);
    }
  }
  if (ncc_count > 0) {
    fmt::print("  mean overlap correlation of the {} neighbour pairs at these positions: {:.3f}\n", ncc_count,
               stitched.mean_overlap_ncc);
  }
  for (const auto& pair : result.pairs) {
    if (pair.accepted && pair.ambiguous) {
      fmt::print("  ambiguous {} - {}: another place matched almost as well (a repeating pattern); the stage's "
                 "prediction chose\n",
                 layout.tiles[static_cast<size_t>(pair.a)].file, layout.tiles[static_cast<size_t>(pair.b)].file);
    }
    if (!pair.accepted) {
      fmt::print("  rejected {} - {}: {}\n", layout.tiles[static_cast<size_t>(pair.a)].file,
                 layout.tiles[static_cast<size_t>(pair.b)].file, pair.rejection);
    }
  }
  if (field) {
    fmt::print("{}", DistortionText(field->fit, field->identified, args.pixel_mm));
    fmt::print("  mean overlap correlation of the undistorted tiles at their positions: {:.3f} (raw tiles, rigid: "
               "{:.3f})\n",
               field->mean_overlap_ncc_after, field->mean_overlap_ncc_before);
  }
  if (accepted == 0) {
    fmt::print("  no pair registered: every tile stays at its nominal position\n");
  }
  if (!fallback.empty()) {
    fmt::print("  at their stage positions (no good pair to an earlier tile): {}\n", fmt::join(fallback, ", "));
  }
  if (!stage_bound.empty()) {
    fmt::print("  registered across but not along parallel marks, where the stage decides (u above {:g} px): {}\n",
               0.5 * options.stage_sigma_px, fmt::join(stage_bound, ", "));
  }
  double worst = 0.0, worst_any = 0.0;
  for (size_t i = 0; i < layout.tiles.size(); ++i) {
    const double u = sigmas[i].maxCoeff();
    if (result.positions.anchor[i] == 0) worst = std::max(worst, u);
    worst_any = std::max(worst_any, u);
  }
  fmt::print("largest standard uncertainty of a registered tile against the first of its chain: {:.4f} px\n", worst);
  if (worst_any > worst) {
    fmt::print("largest standard uncertainty of a tile against the first tile: {:.2f} px (the stage's, where no pair "
               "registered)\n",
               worst_any);
  }
  fmt::print("positions written to {}{}\n", args.output, args.mosaic.empty() ? "" : ", mosaic to " + args.mosaic);
}

}  // namespace

void RegisterStitch(CLI::App& app) {
  auto args = std::make_shared<StitchArgs>();
  CLI::App* sub = app.add_subcommand("stitch", "register overlapping tiles");
  AddDetails(sub,
      "Registers every tile with its right and lower neighbour: the overlap's normalised cross-correlation at every "
      "offset within a quarter of a tile of the nominal one (by Fourier transforms, on a pyramid level), its one "
      "clear peak refined to sub-pixel with the pair's uncertainty; where it has none (a repeating pattern, a "
      "ridge along marks), the phase correlation of the nominal overlap. Tiles that match one on the other better "
      "than anywhere the stage allows (the same image twice) register nothing. Thin overlaps (under 24 px), and the pairs that fail when "
      "too few pass to estimate the stage, are searched instead: phase-correlation candidates within 10 % of a tile "
      "of the nominal offset, each tested by the normalised cross-correlation of the overlap it implies, the best "
      "refined. From the pairs that pass it estimates the stage (step and "
      "sideways drift per column and row, repeatability), searches the failed and disagreeing pairs again within a "
      "few repeatabilities of it, and takes its positions as the stage prior; solves all positions by least squares weighted by those "
      "uncertainties, and writes file,x,y: each tile's top-left corner in pixels (x right, y down), the first tile "
      "of the layout at 0,0, with its standard uncertainty. Tiles that no good pair links to an earlier one keep "
      "their stage (or grid) positions, as the instrument does; along parallel marks, where images cannot tell a "
      "shift, the stage position holds too.");
  sub->add_option("--layout", args->layout, "layout CSV file,row,col[,x,y]; image paths relative to it")->required();
  sub->add_option("--overlap", args->overlap,
                  "nominal overlap of neighbouring tiles in percent, e.g. 20 (a value below 1 is read as a fraction: "
                  "0.2 = 20 %)")
      ->check(OverlapCheck("--overlap"))
      ->required();
  sub->add_option("-o,--output", args->output,
                  "positions CSV file,x,y[,x_mm,y_mm],registered,u_x,u_y (u: standard uncertainty in px against "
                  "the first tile of the chain)")
      ->required();
  sub->add_option("--mosaic", args->mosaic,
                  "also fuse the registered tiles (feathered seams) into one image in the tiles' pixel type (TIFF, "
                  "PNG, EXR; NaN or 0 where no tile reaches), or into an X3P height map in the stage frame when the "
                  "name ends in .x3p (float tiles holding heights in mm; needs --pixel-mm)");
  sub->add_option("--pixel-mm", args->pixel_mm,
                  "pixel size in mm: adds x_mm,y_mm (stage frame, +Y up) and takes nominal positions from the "
                  "layout's x,y")
      ->check(Within(kPixelMm));
  sub->add_option("--min-quality", args->min_quality, "reject pairs whose aligned correlation is below this")
      ->check(Within(-1.0, 1.0))
      ->capture_default_str();
  sub->add_option("--stage-sigma-px", args->stage_sigma_px,
                  "the stage's positioning error over the grid (px, standard deviation): what holds a tile along a "
                  "direction its images do not determine")
      ->check(Within(1e-3, 1e4, "px"))
      ->capture_default_str();
  AddHiddenAlias(sub, "--stage-sigma", args->stage_sigma_px, "--stage-sigma-px");
  AddDistortionOptions(sub, &args->distortion, true);
  sub->add_flag("--json", args->json,
                "print one JSON document {\"tiles\", \"pairs_accepted\", \"pairs_ambiguous\", \"mean_overlap_ncc\", "
                "\"pairs_unresolved\", \"unresolved_warning\" (null unless a quarter of the pairs or more), \"overruled\": "
                "[{\"a\", \"b\", \"registered_px\", \"predicted_px\", \"misclosure_sigma\", \"replaced\"}] (pairs the "
                "grid's loops contradicted, also on stderr), \"loop_birge_ratio\", \"loop_dof\", \"stage_fallback\": [files], "
                "\"stage_along_one_axis\": [files], \"stage_model\": {\"east_step_px\", \"east_drift_px\", "
                "\"south_step_px\", \"south_drift_px\", \"repeatability_px\", ...}, \"pairs\": [{\"a\", \"b\", "
                "\"dx_px\", \"dy_px\", \"sigma_px\", \"quality\", \"accepted\", \"overlap_ncc\", \"ambiguous\", \"unmoved\", \"candidates\": [{\"dx_px\", "
                "\"dy_px\", \"peak\", \"ncc\"}]}]}");
  sub->footer("Example: fvm tiles synthesize -o demo --seed 1 && fvm stitch --layout demo/layout.csv --overlap 20 "
              "-o demo/positions.csv --mosaic demo/mosaic.tif");
  sub->callback([args] { RunStitch(*args); });
}

}  // namespace fvm::cli
