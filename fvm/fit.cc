// fvm fit FILE: finds the calottes in a height map (or an organised point cloud), fits a sphere to each, numbers
// them as the artefact does when told which artefact it is, and writes the centre export stage calibration
// reads (README, "The main job"); with --shape, one sphere or plane to every point (workflows/fit.h).

#include <fmt/core.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "artefacts/io/centre_export.h"
#include "fvm/commands.h"
#include "fvm/summary_output.h"
#include "fvm/surface_read_args.h"
#include "workflows/fit.h"

namespace fvm::cli {
namespace {

struct FitArgs {
  std::string file;
  std::string output;
  bool json = false;
  workflows::SurfaceReadOptions read;  // as fvm info
  workflows::FitOptions options;
};

void RunFit(const FitArgs& args) {
  args.options.Check(!args.output.empty());
  const workflows::FitResult result = workflows::FitFile(args.file, args.read.ToOptions(), args.options);
  if (result.found && !args.output.empty()) {
    artefacts::WriteCentreExport(args.output, workflows::FitCentreExport(result, args.output));
  }
  std::vector<PathKey> paths{{"file", args.file, result.found ? "method" : "robust"}};
  if (result.found && !args.output.empty()) paths.push_back({"output", args.output, ""});
  PrintSummary(workflows::Summarize(result), args.json, paths);
  if (!args.json && result.found && !args.output.empty()) {
    fmt::print("\nwrote {} ({} calottes)\n", args.output, result.found->detection.calottes.size());
  }
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
  sub->add_option("--artefact", args->options.artefact, "number the calottes as this artefact does: grid6x6 or bar17");
  sub->add_option("-o,--output", args->output, "write the centre export (CSV) here");
  sub->add_flag("--json", args->json,
                "print one JSON document {\"calottes\": [{\"id\", \"x\", \"y\", \"z\", \"radius\", \"form_rms_um\", "
                "\"points\", ...}], ...}");
  sub->add_option("--radius-mm", args->options.radius_mm, "fix the sphere radius (the ball that made the calottes), in mm")
      ->check(Within(1e-3, 1e3, "mm"));
  sub->add_option("--rotation-deg", args->options.rotation_deg,
                  "how the artefact lies in the map: its frame turned by this (default 0: calotte 1 at lowest x, "
                  "highest y); needed when two numberings fit equally well, e.g. a bar along y")
      ->check(Within(kAngleDeg));
  sub->add_option("--min-diameter-mm", args->options.min_diameter_mm,
                  "smallest calotte opening (default 0.3 mm, or 0.3 x the artefact's calotte diameter)")
      ->check(Within(1e-3, 1e3, "mm"));
  sub->add_option("--max-diameter-mm", args->options.max_diameter_mm,
                  "largest calotte opening (default 3 mm, or 1.5 x the artefact's calotte diameter)")
      ->check(Within(1e-3, 1e3, "mm"));
  sub->add_option("--min-depth-mm", args->options.min_depth_mm,
                  "depth below the face that counts as inside a calotte (default: 8 x the face's noise, >= 0.5 um)")
      ->check(Within(1e-6, 100.0, "mm"));
  sub->add_option("--residual", args->options.residual,
                  "height: distance over n_z, the maximum-likelihood fit for height-map noise (default); "
                  "orthogonal: plain distance to the sphere, as instrument software fits")
      ->check(CLI::IsMember({"height", "orthogonal"}))
      ->default_str("height");
  sub->add_option("--shape", args->options.shape,
                  "fit one sphere or plane to every point instead of searching calottes (orthogonal-distance least "
                  "squares, ISO 10360-6; from 4 points for a sphere, 3 for a plane), e.g. --shape sphere")
      ->check(CLI::IsMember({"sphere", "plane"}));
  sub->add_flag("--robust", args->options.robust,
                "with --shape: find the shape among stray points (least median of squares over 4-point spheres or "
                "3-point planes, seed 1, then refits without points beyond 3 robust standard deviations until "
                "stable); the points left out are counted in \"outliers\", e.g. --shape sphere --robust");
  AddSurfaceReadOptions(*sub, args->read);
  sub->footer("Example: fvm fit grid.x3p --artefact grid6x6 -o grid.csv\n         fvm fit calotte.ply --json\n"
              "         fvm fit sph1.ds --shape sphere --json\n"
              "         fvm fit scan.xyz --shape sphere --unit m --robust");
  sub->callback([args] { RunFit(*args); });
}

}  // namespace fvm::cli
