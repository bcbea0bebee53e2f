// fvm fit FILE: finds the calottes in a height map (or an organised point cloud), fits a sphere to each, numbers
// them as the artefact does when told which artefact it is, and writes the centre export stage calibration
// reads (README, "The main job").

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "artefacts/geometry/artefact.h"
#include "artefacts/io/centre_export.h"
#include "core/input_error.h"
#include "core/number_text.h"
#include "fvm/commands.h"
#include "fvm/fit_shape.h"
#include "fvm/surface_read_args.h"
#include "workflows/find_calottes.h"
#include "artefacts/io/raw_export_batch.h"
#include "imaging/height_map.h"
#include "imaging/io/surface_file.h"

namespace fvm::cli {
namespace {

struct FitArgs {
  std::string file;
  std::string artefact;
  std::string output;
  bool json = false;
  double radius_mm = 0.0;
  std::optional<double> rotation_deg;
  double min_diameter_mm = 0.0;
  double max_diameter_mm = 0.0;
  double min_depth_mm = 0.0;
  std::string residual = "height";
  SurfaceReadArgs read;  // as fvm info
  std::string shape;     // set: one sphere or plane to every point (fvm/fit_shape.cc) instead of the calotte search
  bool robust = false;
};

std::optional<artefacts::Artefact> NamedArtefact(const std::string& name) {
  if (name.empty()) return std::nullopt;
  return artefacts::KnownArtefact(name);
}

void RunFit(const FitArgs& args) {
  if (!args.shape.empty()) {
    if (!args.artefact.empty() || !args.output.empty() || args.radius_mm > 0) {
      throw InputError("--shape fits one shape to every point and prints it; --artefact, -o and --radius-mm "
                       "belong to the calotte search (leave --shape out for that)");
    }
    RunShapeFit({args.file, args.shape, args.robust, args.json, args.read});
    return;
  }
  if (args.robust) throw InputError("--robust goes with --shape; the calotte search always trims outliers");
  workflows::FindCalottesOptions options;
  options.artefact = NamedArtefact(args.artefact);
  options.radius_mm = args.radius_mm;
  options.rotation_deg = args.rotation_deg;
  options.min_diameter_mm = args.min_diameter_mm;
  options.max_diameter_mm = args.max_diameter_mm;
  options.min_depth_mm = args.min_depth_mm;
  options.residual = args.residual == "orthogonal" ? imaging::SphereResidual::kOrthogonal : imaging::SphereResidual::kHeight;
  const workflows::FoundCalottes found =
      workflows::FindCalottes(imaging::ReadSurface(args.file, args.read.ToOptions()), options, args.file);
  const imaging::CalotteDetection& detection = found.detection;
  const std::optional<artefacts::Artefact>& artefact = found.artefact;
  const std::optional<imaging::LayoutMatch>& layout = found.layout;
  const std::string& method = found.method;
  const std::optional<imaging::HeightMap>& searched_map = found.map;

  artefacts::CentreExport out;
  out.source = args.output;
  out.comments.push_back("fvm fit " + args.file + " (" + method + ")");
  out.comments.push_back(fmt::format(
      "{} calottes{}; sphere fit with the {} residual{}; face noise {:.3f} um", detection.calottes.size(),
      artefact ? " of " + artefact->name + ", numbered by its layout" : "", args.residual,
      args.radius_mm > 0 ? fmt::format(", radius fixed at {} mm", args.radius_mm) : "", detection.face.sigma_mm * 1e3));
  artefacts::AddFoundCentres(detection, out);
  if (!args.output.empty()) artefacts::WriteCentreExport(args.output, out);

  if (args.json) {
    nlohmann::ordered_json doc;
    doc["calottes"] = nlohmann::ordered_json::array();
    for (const auto& c : detection.calottes) {
      const Eigen::Vector3d sd = c.fit.centre_covariance_mm2.diagonal().cwiseSqrt();
      doc["calottes"].push_back(
          {{"id", c.id},
           {"x", RoundTo(c.fit.centre_mm.x(), 1e7)},
           {"y", RoundTo(c.fit.centre_mm.y(), 1e7)},
           {"z", RoundTo(c.fit.centre_mm.z(), 1e7)},
           {"radius", RoundTo(c.fit.radius_mm, 1e7)},
           {"form_rms_um", RoundTo(c.fit.rms_deviation_mm * 1e3, 1e4)},
           {"points", c.fit.inliers},
           {"u_um", {RoundTo(sd.x() * 1e3, 1e4), RoundTo(sd.y() * 1e3, 1e4), RoundTo(sd.z() * 1e3, 1e4)}},
           {"min_dev_um", RoundTo(c.fit.min_deviation_mm * 1e3, 1e4)},
           {"max_dev_um", RoundTo(c.fit.max_deviation_mm * 1e3, 1e4)},
           {"mean_dev_um", RoundTo(c.fit.mean_deviation_mm * 1e3, 1e4)},
           {"outliers", c.fit.points - c.fit.inliers},
           {"converged", c.fit.converged},
           {"fit_stop", c.fit.stop_reason},
           {"at_border", c.at_border}});
    }
    doc["file"] = args.file;
    doc["method"] = method;
    doc["artefact"] = artefact ? nlohmann::ordered_json(artefact->name) : nlohmann::ordered_json(nullptr);
    doc["face"] = {{"slope_x", detection.face.b},
                   {"slope_y", detection.face.c},
                   {"sigma_um", RoundTo(detection.face.sigma_mm * 1e3, 1e4)}};
    if (layout) {
      doc["layout"] = {{"rotation_deg", RoundTo(layout->rotation_rad * 180 / M_PI, 1e6)},
                       {"scale", RoundTo(layout->scale, 1e9)},
                       {"rms_um", RoundTo(layout->rms_mm * 1e3, 1e4)}};
    }
    doc["rejected"] = nlohmann::ordered_json::array();
    for (const auto& r : detection.rejected) {
      doc["rejected"].push_back(
          {{"x", RoundTo(r.centre_mm.x(), 1e4)}, {"y", RoundTo(r.centre_mm.y(), 1e4)}, {"reason", r.reason}});
    }
    if (!args.output.empty()) doc["output"] = args.output;
    fmt::print("{}\n", doc.dump(2));
    return;
  }

  if (searched_map) {
    fmt::print("{}: {} x {} points of {:.3g} x {:.3g} um; face noise {:.3f} um, tilt ({:.3g}, {:.3g}) mrad\n", args.file,
               searched_map->size_x, searched_map->size_y, searched_map->dx_mm * 1e3, searched_map->dy_mm * 1e3,
               detection.face.sigma_mm * 1e3, detection.face.b * 1e3, detection.face.c * 1e3);
  } else {
    fmt::print("{}: unorganised cloud, calottes found by {}; face noise {:.3f} um, tilt ({:.3g}, {:.3g}) mrad\n",
               args.file, method, detection.face.sigma_mm * 1e3, detection.face.b * 1e3, detection.face.c * 1e3);
  }
  if (layout) {
    fmt::print("{} layout: turned {:.3f} deg, scale {:.6f}, {:.2f} um rms from nominal\n", artefact->name,
               layout->rotation_rad * 180 / M_PI, layout->scale, layout->rms_mm * 1e3);
  }
  fmt::print("\n{:>4}  {:>12}  {:>12}  {:>12}  {:>10}  {:>8}  {:>20}  {:>8}\n", "id", "x [mm]", "y [mm]", "z [mm]",
             "r [mm]", "form [um]", "u(x, y, z) [um]", "points");
  for (const auto& c : detection.calottes) {
    const Eigen::Vector3d sd = c.fit.centre_covariance_mm2.diagonal().cwiseSqrt() * 1e3;
    fmt::print("{:>4}  {:>12.6f}  {:>12.6f}  {:>12.6f}  {:>10.6f}  {:>9.3f}  {:>6.3f} {:>6.3f} {:>6.3f}  {:>8}{}\n",
               c.id, c.fit.centre_mm.x(), c.fit.centre_mm.y(), c.fit.centre_mm.z(), c.fit.radius_mm,
               c.fit.rms_deviation_mm * 1e3, sd.x(), sd.y(), sd.z(), c.fit.inliers,
               c.at_border ? "  cut by the map's border" : "");
    if (!c.fit.converged) fmt::print("      calotte {}: the sphere fit did NOT converge ({})\n", c.id, c.fit.stop_reason);
  }
  for (const auto& r : detection.rejected) {
    fmt::print("not a calotte at ({:.3f}, {:.3f}) mm: {}\n", r.centre_mm.x(), r.centre_mm.y(), r.reason);
  }
  if (artefact && detection.calottes.size() < artefact->calottes.size()) {
    std::string missing;
    for (const auto& n : artefact->calottes) {
      bool seen = false;
      for (const auto& c : detection.calottes) seen = seen || c.id == n.id;
      if (!seen) missing += (missing.empty() ? "" : ", ") + std::to_string(n.id);
    }
    fmt::print("not in this map: calotte {}\n", missing);
  }
  if (!args.output.empty()) fmt::print("\nwrote {} ({} calottes)\n", args.output, detection.calottes.size());
}

}  // namespace

void RegisterFit(CLI::App& app) {
  auto args = std::make_shared<FitArgs>();
  CLI::App* sub = app.add_subcommand("fit", "find calottes and fit spheres; writes a centre export");
  AddDetails(sub,
      "Finds the calottes (spherical dimples) in a height map: levels the face they are cut into, takes the round "
      "depressions below it, and fits a sphere to the points of each by least squares with outliers trimmed. "
      "An unorganised point cloud (PLY, PCD, XYZ as MeasureSuite, Gwyddion or CloudCompare export it) seen from "
      "above (2.5D) is projected onto a grid of about four points per cell to find the face and the dimples with "
      "the same screening, then each sphere is fitted to the cloud's own points with the same estimator; the "
      "output says which method was used. A cloud of one calotte in its face gives that calotte. "
      "With --artefact the calottes get the artefact's numbers (1..36 row by row for grid6x6, 1..17 along bar17), "
      "matched to its nominal layout. Prints centre, radius, form deviation (RMS) and the centre's standard "
      "uncertainty per calotte; -o writes the centre export (CSV id,x,y,z,radius,form_rms in mm) that fvm "
      "calibrate reads. Reads what fvm info reads. "
      "With --shape sphere|plane it fits one shape to all points of any cloud or surface (a CMM probing of a "
      "reference sphere, a tracker nest, a cap or a flat of a few dozen points; XYZ text including NIST's .ds "
      "sets whose first line is the count, PLY, PCD, height maps): orthogonal-distance least squares from a "
      "closed-form start, converged to the last digits of double, with standard uncertainties from the "
      "residuals. JSON: sphere {\"shape\", \"points\", \"centre_mm\", \"radius_mm\", \"u_centre_um\", "
      "\"u_radius_um\", \"rms_um\", \"outliers\"}; plane {\"shape\", \"points\", \"point_mm\" (centroid), "
      "\"normal\" (unit), \"u_normal_urad\", \"rms_um\", \"outliers\"}.");
  sub->add_option("FILE", args->file, "height map (X3P, AL3D, TIFF/EXR/PNG) or point cloud (PLY, PCD, XYZ)")->required();
  sub->add_option("--artefact", args->artefact, "number the calottes as this artefact does: grid6x6 or bar17");
  sub->add_option("-o,--output", args->output, "write the centre export (CSV) here");
  sub->add_flag("--json", args->json,
                "print one JSON document {\"calottes\": [{\"id\", \"x\", \"y\", \"z\", \"radius\", \"form_rms_um\", "
                "\"points\", ...}], ...}");
  sub->add_option("--radius-mm", args->radius_mm, "fix the sphere radius (the ball that made the calottes), in mm")
      ->check(Within(1e-3, 1e3, "mm"));
  sub->add_option("--rotation-deg", args->rotation_deg,
                  "how the artefact lies in the map: its frame turned by this (default 0: calotte 1 at lowest x, "
                  "highest y); needed when two numberings fit equally well, e.g. a bar along y")
      ->check(Within(kAngleDeg));
  sub->add_option("--min-diameter-mm", args->min_diameter_mm,
                  "smallest calotte opening (default 0.3 mm, or 0.3 x the artefact's calotte diameter)")
      ->check(Within(1e-3, 1e3, "mm"));
  sub->add_option("--max-diameter-mm", args->max_diameter_mm,
                  "largest calotte opening (default 3 mm, or 1.5 x the artefact's calotte diameter)")
      ->check(Within(1e-3, 1e3, "mm"));
  sub->add_option("--min-depth-mm", args->min_depth_mm,
                  "depth below the face that counts as inside a calotte (default: 8 x the face's noise, >= 0.5 um)")
      ->check(Within(1e-6, 100.0, "mm"));
  sub->add_option("--residual", args->residual,
                  "height: distance over n_z, the maximum-likelihood fit for height-map noise (default); "
                  "orthogonal: plain distance to the sphere, as instrument software fits")
      ->check(CLI::IsMember({"height", "orthogonal"}))
      ->default_str("height");
  sub->add_option("--shape", args->shape,
                  "fit one sphere or plane to every point instead of searching calottes (orthogonal-distance least "
                  "squares, ISO 10360-6; from 4 points for a sphere, 3 for a plane), e.g. --shape sphere")
      ->check(CLI::IsMember({"sphere", "plane"}));
  sub->add_flag("--robust", args->robust,
                "with --shape: find the shape among stray points (least median of squares over 4-point spheres or "
                "3-point planes, seed 1, then refits without points beyond 3 robust standard deviations until "
                "stable); the points left out are counted in \"outliers\", e.g. --shape sphere --robust");
  args->read.AddOptions(*sub);
  sub->footer("Example: fvm fit grid.x3p --artefact grid6x6 -o grid.csv\n         fvm fit calotte.ply --json\n"
              "         fvm fit sph1.ds --shape sphere --json\n"
              "         fvm fit scan.xyz --shape sphere --unit m --robust");
  sub->callback([args] { RunFit(*args); });
}

}  // namespace fvm::cli
