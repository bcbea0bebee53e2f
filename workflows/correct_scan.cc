#include "workflows/correct_scan.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "core/input_error.h"
#include "core/number_text.h"
#include "core/statistics.h"

namespace fvm::workflows {
namespace {

// The median height of a tile's valid points: where the tile's rigid shift is evaluated along z.
double MedianZ(const imaging::PointCloud& cloud) {
  std::vector<double> z;
  for (const Eigen::Vector3d& p : cloud.points) {
    if (p.allFinite()) z.push_back(p.z());
  }
  return HighMedian(std::move(z));
}

constexpr std::size_t kNamedPoints = 5;  // points a message names before "and N more"

std::string Point3(const Eigen::Vector3d& p) { return fmt::format("({:.4f}, {:.4f}, {:.4f})", p.x(), p.y(), p.z()); }

// "point 12" in file order, or "point (column 3, row 7)" on a grid: how a user finds it in the file.
std::string PointName(const imaging::PointCloud& cloud, std::size_t i) {
  if (!cloud.IsOrganised()) return fmt::format("point {}", i + 1);
  return fmt::format("point (column {}, row {})", i % static_cast<std::size_t>(cloud.width),
                     i / static_cast<std::size_t>(cloud.width));
}

std::string TravelText(const stage::ParameterLayout& layout) {
  const auto& t = layout.travel();
  return fmt::format("x {}..{}, y {}..{} mm", FormatShortest(t[0].min), FormatShortest(t[0].max),
                     FormatShortest(t[1].min), FormatShortest(t[1].max));
}

}  // namespace

std::vector<std::size_t> CheckTravel(const ScanCorrectionJob& job, const stage::Calibration& cal,
                                     const imaging::PointCloud& cloud, const std::string& name,
                                     const std::vector<std::string>& tile_names) {
  const std::vector<std::size_t> outside = stage::PointsOutsideTravel(cal.layout, cloud.points, job.options.origin_mm);
  if (outside.empty() || job.extrapolate) return outside;
  std::string named;
  for (std::size_t k = 0; k < std::min(outside.size(), kNamedPoints); ++k) {
    const std::size_t i = outside[k];
    named += fmt::format("\n  {} at stage {} mm", tile_names.empty() ? PointName(cloud, i) : "tile " + tile_names[i],
                         Point3(cloud.points[i] + job.options.origin_mm));
  }
  if (outside.size() > kNamedPoints) named += fmt::format("\n  and {} more", outside.size() - kNamedPoints);
  const std::string fix = tile_names.empty()
                              ? "If the file's coordinates are not stage coordinates (an origin at the dataset's "
                                "corner), give the stage position of its origin with --origin X,Y,Z; to correct them "
                                "anyway, add --extrapolate"
                              : "The layout's x, y must be the tiles' stage positions (encoder readings); to correct "
                                "them anyway, add --extrapolate";
  throw InputError(fmt::format(
      "{}: {} of its {} lie outside the travel {} was identified on ({}), where the model only extrapolates:{}\n{}",
      name, outside.size(), tile_names.empty() ? "points" : "tiles", job.calibration_name, TravelText(cal.layout), named,
      fix));
}

std::vector<Eigen::Vector3d> UncertaintiesAt(const stage::ScanCorrector& corrector,
                                             const std::vector<Eigen::Vector3d>& points) {
  std::vector<Eigen::Vector3d> u;
  u.reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    u.push_back(p.allFinite() ? Eigen::Vector3d(corrector.Correct(p).covariance.diagonal().cwiseMax(0.0).cwiseSqrt())
                              : Eigen::Vector3d::Constant(NAN));
  }
  return u;
}

CorrectedCloud CorrectCloud(imaging::PointCloud& cloud, const stage::Calibration& calibration,
                            const ScanCorrectionJob& job, const std::string& name, bool with_uncertainty) {
  std::vector<std::size_t> outside = CheckTravel(job, calibration, cloud, name);
  CorrectedCloud out{stage::ScanCorrector(calibration, job.options, cloud.points), {}, {}, std::move(outside)};
  out.summary = stage::CorrectScanInPlace(out.corrector, cloud.points, with_uncertainty ? &out.u : nullptr, job.threads);
  if (out.summary.corrected == 0) throw InputError(name + ": no valid point to correct (every point is NaN or infinite)");
  return out;
}

TileCorrection CorrectTiles(const std::vector<TileInput>& tiles, const stage::Calibration& calibration,
                            const ScanCorrectionJob& job, const std::string& name) {
  TileCorrection out;
  for (const TileInput& tile : tiles) {
    const imaging::PointCloudStats stats = imaging::ComputeStats(*tile.cloud);
    if (stats.valid_points == 0) throw InputError(tile.path + ": no valid point in the tile");
    TileShift t;
    t.file = tile.file;
    t.centre = Eigen::Vector3d(tile.stage_xy_mm.x(), tile.stage_xy_mm.y(), MedianZ(*tile.cloud) + job.options.origin_mm.z());
    // The tile's footprint about its centre, to say how far one shift is from correcting every point.
    t.per_point_mm = 0.5 * (stats.max - stats.min).head<2>().norm();
    out.tiles.push_back(t);
  }
  std::vector<Eigen::Vector3d> centres;
  std::vector<std::string> names;
  for (const TileShift& t : out.tiles) centres.push_back(t.centre), names.push_back(t.file);
  ScanCorrectionJob at_stage = job;
  at_stage.options.origin_mm.setZero();  // layout positions are stage positions
  out.outside = CheckTravel(at_stage, calibration, imaging::MakeUnorganisedCloud(centres), name, names);
  const stage::ScanCorrector corrector(calibration, at_stage.options, centres);
  if (corrector.first_tile()) out.first_tile_mm = corrector.first_tile()->frame().first_tile;
  for (TileShift& t : out.tiles) {
    const stage::CorrectedPoint c = corrector.Correct(t.centre);
    t.shift = c.position - t.centre;
    t.u = c.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    const double half = t.per_point_mm / std::sqrt(2.0);
    t.per_point_mm = 0.0;
    for (const Eigen::Vector3d& corner : {Eigen::Vector3d(-half, -half, 0), Eigen::Vector3d(half, -half, 0),
                                          Eigen::Vector3d(-half, half, 0), Eigen::Vector3d(half, half, 0)}) {
      t.per_point_mm = std::max(t.per_point_mm, (corrector.Shift(t.centre + corner) - t.shift).norm());
    }
    out.largest_per_point_mm = std::max(out.largest_per_point_mm, t.per_point_mm);
  }
  return out;
}

}  // namespace fvm::workflows
