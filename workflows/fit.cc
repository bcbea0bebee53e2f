#include "workflows/fit.h"

#include <fmt/core.h>

#include <utility>
#include <vector>

#include "artefacts/io/raw_export_batch.h"
#include "core/exit_codes.h"
#include "core/input_error.h"
#include "imaging/point_cloud.h"

namespace fvm::workflows {
namespace {

// The points of a surface: an unorganised cloud's as they are (a NaN there is bad input, which the fit names);
// a height map's or an organised cloud's valid points (NaN marks a missing grid point there).
std::vector<Eigen::Vector3d> PointsToFit(imaging::Surface surface) {
  imaging::PointCloud cloud =
      surface.height_map ? imaging::HeightMapToCloud(*surface.height_map) : std::move(*surface.cloud);
  if (!cloud.IsOrganised()) return std::move(cloud.points);
  std::vector<Eigen::Vector3d> valid;
  for (const auto& p : cloud.points) {
    if (p.allFinite()) valid.push_back(p);
  }
  return valid;
}

imaging::ShapeFit FitOneShape(const std::string& file, const imaging::SurfaceReadOptions& read,
                              const FitOptions& options) {
  imaging::ShapeFitOptions shape;
  shape.shape = options.shape == "plane" ? imaging::Shape::kPlane : imaging::Shape::kSphere;
  shape.robust = options.robust;
  try {
    return imaging::FitShape(PointsToFit(imaging::ReadSurface(file, read)), shape);
  } catch (const InputError& e) {
    const std::string what = e.what();
    throw InputError(what.rfind(file, 0) == 0 ? what : file + ": " + what);
  } catch (const NotConvergedError& e) {
    throw NotConvergedError(file + ": " + e.what());
  }
}

}  // namespace

void FitOptions::Check(bool writes_output) const {
  if (!shape.empty() && shape != "sphere" && shape != "plane") {
    throw InputError("--shape '" + shape + "': use sphere or plane");
  }
  if (residual != "height" && residual != "orthogonal") {
    throw InputError("--residual '" + residual + "': use height or orthogonal");
  }
  if (!shape.empty()) {
    if (!artefact.empty() || writes_output || radius_mm > 0) {
      throw InputError("--shape fits one shape to every point and prints it; --artefact, -o and --radius-mm "
                       "belong to the calotte search (leave --shape out for that)");
    }
  } else if (robust) {
    throw InputError("--robust goes with --shape; the calotte search always trims outliers");
  }
}

FindCalottesOptions FitOptions::CalotteSearch() const {
  FindCalottesOptions o;
  if (!artefact.empty()) o.artefact = artefacts::KnownArtefact(artefact);
  o.radius_mm = radius_mm;
  o.rotation_deg = rotation_deg;
  o.min_diameter_mm = min_diameter_mm;
  o.max_diameter_mm = max_diameter_mm;
  o.min_depth_mm = min_depth_mm;
  o.residual = residual == "orthogonal" ? imaging::SphereResidual::kOrthogonal : imaging::SphereResidual::kHeight;
  return o;
}

FitResult FitFile(const std::string& file, const imaging::SurfaceReadOptions& read, const FitOptions& options) {
  options.Check();
  FitResult r{file, options, std::nullopt, std::nullopt};
  if (!options.shape.empty()) {
    r.shape = FitOneShape(file, read, options);
  } else {
    const FindCalottesOptions search = options.CalotteSearch();  // an unknown artefact before the file is read
    r.found = FindCalottes(imaging::ReadSurface(file, read), search, file);
  }
  return r;
}

artefacts::CentreExport FitCentreExport(const FitResult& result, const std::string& output) {
  if (!result.found) throw InputError("--shape fits one shape; only the calotte search writes a centre export");
  const FoundCalottes& found = *result.found;
  const FitOptions& o = result.options;
  artefacts::CentreExport out;
  out.source = output;
  out.comments.push_back("fvm fit " + result.file + " (" + found.method + ")");
  out.comments.push_back(fmt::format(
      "{} calottes{}; sphere fit with the {} residual{}; face noise {:.3f} um", found.detection.calottes.size(),
      found.artefact ? " of " + found.artefact->name + ", numbered by its layout" : "", o.residual,
      o.radius_mm > 0 ? fmt::format(", radius fixed at {} mm", o.radius_mm) : "", found.detection.face.sigma_mm * 1e3));
  artefacts::AddFoundCentres(found.detection, out);
  return out;
}

}  // namespace fvm::workflows
