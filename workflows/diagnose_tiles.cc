#include "workflows/diagnose_tiles.h"

#include <fmt/core.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>

#include "core/input_error.h"
#include "workflows/calibration_scans.h"
#include "workflows/overlap_band_matching.h"
#include "workflows/stitch.h"
#include "workflows/stitch_layout.h"

namespace fvm::workflows {

void TileDiagnoseOptions::Check() const {
  if (layout.empty() == scans.empty()) {
    throw InputError("fvm diagnose: give a batch directory, or tiles: --layout L.csv (one grid) or --scan L.csv "
                     "(calibration scans), not both");
  }
  if (!layout.empty() && !(overlap > 0.0 && overlap < 1.0)) {
    throw InputError("--overlap: --layout needs the tiles' nominal overlap, e.g. --overlap 10 (percent)");
  }
  if (!scans.empty() && !(pixel_mm > 0.0)) {
    throw InputError("--pixel-mm: --scan needs the pixel size in mm (the encoders' readings place the tiles)");
  }
  if (!(pixel_mm >= 0.0) || !std::isfinite(pixel_mm)) throw InputError(fmt::format("--pixel-mm {}: give a size in mm", pixel_mm));
  if (order < 2 || order > imaging::kMaxDistortionOrder) {
    throw InputError(fmt::format("--order {}: the field model's order is 2 .. {}", order, imaging::kMaxDistortionOrder));
  }
  if (!(alpha >= 1e-6 && alpha <= 0.5)) throw InputError(fmt::format("--alpha: {} is outside 1e-06 .. 0.5", alpha));
  if (threads < 0) throw InputError(fmt::format("--threads {}: give 0 (all cores) or more", threads));
  matching.Check();
}

namespace {

// Every registered overlap's correspondences, the tiles' rigid positions (one index space over all scans) and the
// tiles that hold; and how many neighbour pairs there were.
struct OverlapPoints : RegisteredOverlapPoints {
  int pairs = 0;
};

void AddRegisteredSet(const std::vector<imaging::TileImage>& images, const std::vector<imaging::PairRegistration>& pairs,
                      const imaging::TilePositions& positions, const imaging::CorrespondenceOptions& matching,
                      const std::string& set, OverlapPoints& out) {
  out.pairs += static_cast<int>(pairs.size());
  AppendRegisteredSet(images, pairs, positions, imaging::FieldDistortion{}, matching, set, out);
}

OverlapPoints GatherOverlapPoints(const TileDiagnoseOptions& options) {
  OverlapPoints out;
  if (!options.layout.empty()) {
    const LayoutTiles tiles = ReadLayoutTiles(options.layout, options.threads, options.overlap);
    StitchOptions stitch;
    stitch.overlap = options.overlap;
    stitch.pixel_mm = options.pixel_mm;
    stitch.threads = options.threads;
    const StitchResult rigid = StitchTiles(tiles.layout, tiles.images, stitch);
    AddRegisteredSet(tiles.images, rigid.registration.pairs, rigid.registration.positions, options.matching,
                     "--layout " + options.layout, out);
    return out;
  }
  ReadAndRegisterScans(options.scans, options.pixel_mm, options.threads, false,
                       [&](const artefacts::RegisteredScan& scan, const std::vector<imaging::TileImage>& images) {
                         AddRegisteredSet(images, scan.registration.pairs, scan.registration.positions, options.matching,
                                          "--scan: scan " + scan.name, out);
                       });
  return out;
}

// One correspondence's misclosure under positions p and field d: p_a - p_b + u_a - u_b + d(u_a) - d(u_b) (px).
Eigen::Vector2d Misclosure(const imaging::PairCorrespondences& p, size_t m, const std::vector<Eigen::Vector2d>& positions,
                           const imaging::FieldDistortion& field) {
  Eigen::Vector2d r = positions[static_cast<size_t>(p.a)] - positions[static_cast<size_t>(p.b)] + p.a_px[m] - p.b_px[m];
  if (!field.Identity()) r += field.Displacement(p.a_px[m], p.kernel) - field.Displacement(p.b_px[m], p.kernel);
  return r;
}

// The points both models are judged on: in pairs the field fit weighs, within 3 sigma of the field model (the few
// that tracked the wrong speckle out of both).
using Inliers = std::vector<std::vector<size_t>>;  // per pair, the indices of its points
Inliers SharedInliers(const OverlapPoints& points, const imaging::FieldDistortionFit& fit, int min_points) {
  Inliers inliers(points.matched.size());
  const double bound = 3.0 * fit.point_sigma_px;
  for (size_t q = 0; q < points.matched.size(); ++q) {
    const imaging::PairCorrespondences& p = points.matched[q];
    if (static_cast<int>(p.a_px.size()) < min_points) continue;
    for (size_t m = 0; m < p.a_px.size(); ++m) {
      if (Misclosure(p, m, fit.positions_px, fit.field).cwiseAbs().maxCoeff() <= bound) inliers[q].push_back(m);
    }
  }
  return inliers;
}

// The rigid model on the same points: the positions by least squares, the fixed tiles held. Each axis is the same
// graph Laplacian; a vanishing pull towards the rigid registration's positions fixes what no point reaches.
std::vector<Eigen::Vector2d> RigidPositions(const OverlapPoints& points, const Inliers& inliers) {
  const size_t n = points.initial.size();
  constexpr double kPull = 1e-9;
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixX2d rhs = Eigen::MatrixX2d::Zero(static_cast<Eigen::Index>(n), 2);
  for (size_t i = 0; i < n; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    entries.emplace_back(k, k, points.fixed[i] ? 1.0 : kPull);
    rhs.row(k) = (points.fixed[i] ? 1.0 : kPull) * points.initial[i].transpose();
  }
  for (size_t q = 0; q < points.matched.size(); ++q) {
    const imaging::PairCorrespondences& p = points.matched[q];
    const auto a = static_cast<Eigen::Index>(p.a), b = static_cast<Eigen::Index>(p.b);
    const bool free_a = !points.fixed[static_cast<size_t>(p.a)], free_b = !points.fixed[static_cast<size_t>(p.b)];
    for (size_t m : inliers[q]) {
      // e = p_a - p_b + (u_a - u_b): the fixed tiles' positions are part of the constant.
      Eigen::Vector2d constant = p.a_px[m] - p.b_px[m];
      if (!free_a) constant += points.initial[static_cast<size_t>(p.a)];
      if (!free_b) constant -= points.initial[static_cast<size_t>(p.b)];
      if (free_a) entries.emplace_back(a, a, 1.0), rhs.row(a) -= constant.transpose();
      if (free_b) entries.emplace_back(b, b, 1.0), rhs.row(b) += constant.transpose();
      if (free_a && free_b) entries.emplace_back(a, b, -1.0), entries.emplace_back(b, a, -1.0);
    }
  }
  Eigen::SparseMatrix<double> normal(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  normal.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  const Eigen::MatrixX2d solved = solver.solve(rhs);
  std::vector<Eigen::Vector2d> positions(n);
  for (size_t i = 0; i < n; ++i) positions[i] = points.fixed[i] ? points.initial[i] : solved.row(static_cast<Eigen::Index>(i)).transpose();
  return positions;
}

OverlapResiduals ResidualsOf(const OverlapPoints& points, const Inliers& inliers, const std::vector<Eigen::Vector2d>& positions,
                             const imaging::FieldDistortion& field, double* sum_squares) {
  OverlapResiduals out;
  double squares = 0.0, sum = 0.0;
  for (size_t q = 0; q < points.matched.size(); ++q) {
    for (size_t m : inliers[q]) {
      const double r = Misclosure(points.matched[q], m, positions, field).norm();
      squares += r * r, sum += r, ++out.points;
    }
  }
  if (out.points > 0) out.rms_px = std::sqrt(squares / out.points), out.mean_px = sum / out.points;
  *sum_squares = squares;
  return out;
}

}  // namespace

TileDiagnosis DiagnoseTiles(const TileDiagnoseOptions& options) {
  options.Check();
  imaging::SetImagingThreads(options.threads);
  const OverlapPoints points = GatherOverlapPoints(options);
  TileDiagnosis d;
  d.source = options.layout.empty() ? "scan" : "layout";
  d.tiles = static_cast<int>(points.initial.size());
  d.pairs = points.pairs;
  d.width_px = points.width, d.height_px = points.height;
  imaging::FieldDistortionFitOptions fit_options;
  fit_options.order = options.order;
  // A grid is placed by its overlaps alone: the terms that act on them as a stretch of the mosaic hold, as in fvm
  // stitch; scans keep them, as fvm calibrate --scan does (the encoders place the tiles).
  fit_options.hold_stretch_terms = d.source == "layout";
  fit_options.threads = std::max(1, options.threads);
  try {
    d.field = imaging::FitFieldDistortion(points.matched, points.initial, points.fixed, points.width, points.height,
                                          fit_options);
  } catch (const imaging::FieldDistortionUndeterminable& e) {
    throw InputError(fmt::format("--order {}: the overlaps cannot test a field distortion: {}", options.order, e.what()));
  }
  d.pairs_used = d.field.pairs_used;
  d.point_sigma_px = d.field.point_sigma_px;
  d.largest_px = d.field.field.LargestDisplacementPx();

  const Inliers inliers = SharedInliers(points, d.field, fit_options.min_pair_points);
  double rss_rigid = 0.0, rss_field = 0.0;
  d.rigid = ResidualsOf(points, inliers, RigidPositions(points, inliers), imaging::FieldDistortion{}, &rss_rigid);
  d.with_field = ResidualsOf(points, inliers, d.field.positions_px, d.field.field, &rss_field);

  d.extra_parameters = static_cast<int>(d.field.field.coefficients.size() - d.field.held_terms.size());
  d.noise_factor = std::max(d.field.block_scatter_factor, d.field.pair_scatter_factor);
  const double noise = d.point_sigma_px * d.noise_factor;
  const int denominator_dof = d.field.block_dof > 0 ? d.field.block_dof : std::max(1, 2 * d.with_field.points - d.extra_parameters);
  if (d.extra_parameters > 0 && noise > 0.0 && rss_rigid > rss_field) {
    d.f_statistic = (rss_rigid - rss_field) / d.extra_parameters / (noise * noise);
    const boost::math::fisher_f distribution(d.extra_parameters, denominator_dof);
    d.p_value = boost::math::cdf(boost::math::complement(distribution, d.f_statistic));
  }
  const double observations = 2.0 * d.with_field.points / (d.noise_factor * d.noise_factor);
  if (rss_rigid > 0.0 && rss_field > 0.0) {
    d.delta_bic = observations * std::log(rss_field / rss_rigid) + d.extra_parameters * std::log(observations);
  }
  d.significant = d.p_value < options.alpha && d.delta_bic < 0.0;
  return d;
}

}  // namespace fvm::workflows
