#include "workflows/scan_distortion.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "core/input_error.h"
#include "core/progress.h"
#include "imaging/field_distortion_evidence.h"
#include "imaging/io/tile_layout.h"
#include "imaging/tile_pair_registration.h"
#include "imaging/tile_registration.h"
#include "workflows/calibration_scans.h"
#include "workflows/overlap_band_matching.h"

namespace fvm::workflows {
namespace {

// A registered pair of one scan whose overlap gave the field fit too few correspondences to place its tiles (a
// diagonal's corner overlap, a thin or texture-poor band): its offset is registered again on the undistorted tiles.
struct PairToRegisterAgain {
  size_t scan, pair;
};

// The pair registered again on its two tiles resampled without the field: the same registration as the rigid one,
// so the undistorted offset and its information come from the whole overlap. Rejected (with the reason) when the
// undistorted tiles do not register: better a pair missing from the calibration than one biased by the field.
void RegisterUndistortedPair(const imaging::TileImage& a, const imaging::TileImage& b,
                             const imaging::FieldDistortion& field, imaging::PairRegistration& pair) {
  const imaging::PairRegistration again =
      imaging::RegisterPair(imaging::UndistortTile(a, field), imaging::UndistortTile(b, field), pair.offset_px, {});
  if (again.accepted) {
    pair.offset_px = again.offset_px;
    pair.information = again.information;
    pair.quality = again.quality;
  } else {
    pair.accepted = false;
    pair.rejection = "registered, but not once undistorted (" + again.rejection + ")";
  }
}

// How an offset between undistorted tiles moves with the field's coefficients: p_b - p_a = u_a - u_b + d(u_a) - d(u_b)
// averaged over the points that placed it, so the mean of B(u_a) - B(u_b) over them (px per px of coefficient),
// each read as the fit read it: through the window the point was matched on (`kernel`; none for a registration of
// whole undistorted tiles, which moves each pixel by the field there).
Eigen::Matrix<double, 2, Eigen::Dynamic> FieldSensitivity(const imaging::FieldDistortion& field,
                                                          const std::vector<Eigen::Vector2d>& a_px,
                                                          const std::vector<Eigen::Vector2d>& b_px,
                                                          const imaging::FieldKernel& kernel = {}) {
  Eigen::Matrix<double, 2, Eigen::Dynamic> sum = Eigen::Matrix<double, 2, Eigen::Dynamic>::Zero(2, field.coefficients.size());
  for (size_t m = 0; m < a_px.size(); ++m) sum += field.Basis(a_px[m], kernel) - field.Basis(b_px[m], kernel);
  return a_px.empty() ? sum : Eigen::Matrix<double, 2, Eigen::Dynamic>(sum / static_cast<double>(a_px.size()));
}

// The same for a pair registered again on undistorted tiles: over a 9 x 9 grid of the overlap at `offset_px`.
Eigen::Matrix<double, 2, Eigen::Dynamic> FieldSensitivityOverOverlap(const imaging::FieldDistortion& field,
                                                                     const Eigen::Vector2d& offset_px) {
  const Eigen::Vector2d low = offset_px.cwiseMax(0.0);
  const Eigen::Vector2d high = (offset_px + Eigen::Vector2d(field.width_px - 1, field.height_px - 1))
                                   .cwiseMin(Eigen::Vector2d(field.width_px - 1, field.height_px - 1));
  std::vector<Eigen::Vector2d> a_px, b_px;
  for (int j = 0; j <= 8; ++j) {
    for (int i = 0; i <= 8; ++i) {
      a_px.push_back(low + (high - low).cwiseProduct(Eigen::Vector2d(i, j) / 8.0));
      b_px.push_back(a_px.back() - offset_px);
    }
  }
  return FieldSensitivity(field, a_px, b_px);
}

}  // namespace

std::vector<artefacts::RegisteredScan> ReadAndRegisterUndistortedScans(const std::vector<std::string>& layouts,
                                                                       double pixel_mm, int threads, bool progress,
                                                                       const ScanDistortionOptions& options,
                                                                       ScanDistortion* field) {
  if (!options.known) imaging::FieldDistortionTermNames(options.order);  // throws outside 2..6
  options.matching.Check();
  options.fit.Check();
  // Pairs the fit cannot place (fewer correspondences than it weighs), with their tiles kept for the second
  // registration; the pairs it places, each scan's in a set.
  RegisteredOverlapPoints points;
  std::vector<PairToRegisterAgain> again;
  std::map<int, imaging::TileImage> kept;
  // One scan's accepted overlaps matched from `guess`, at the offsets `pairs` give.
  const auto append = [&](size_t scan_index, const std::string& name, const std::vector<imaging::TileImage>& images,
                          const std::vector<imaging::PairRegistration>& pairs, const imaging::TilePositions& positions,
                          const imaging::FieldDistortion& guess) {
    const int base = static_cast<int>(points.initial.size());
    const size_t first = points.matched.size();
    const std::vector<size_t> pair_of_overlap = AppendRegisteredSet(images, pairs, positions, guess, options.matching,
                                                                    "--distortion: scan " + name, points);
    for (size_t m = 0; m < pair_of_overlap.size(); ++m) {
      const imaging::PairCorrespondences& p = points.matched[first + m];
      if (static_cast<int>(p.a_px.size()) < options.fit.min_pair_points) {
        again.push_back({scan_index, pair_of_overlap[m]});
        for (int t : {p.a, p.b}) kept.emplace(t, images[static_cast<size_t>(t - base)]);
      }
    }
  };
  const auto fit = [&](const imaging::FieldDistortion* known) {
    try {
      imaging::FieldDistortionFitOptions fit_options = options.fit;
      fit_options.order = known ? known->order : options.order;
      // Identified: the non-radial own-axis cubic terms only when the overlaps show them
      // (imaging/field_distortion_evidence.h): a chain of tiles pins them only through the curvature of the step.
      return known ? imaging::FitFieldDistortion(points.matched, points.initial, points.fixed, points.width,
                                                 points.height, fit_options, known)
                   : imaging::FitFieldDistortionByEvidence(points.matched, points.initial, points.fixed, points.width,
                                                           points.height, fit_options);
    } catch (const imaging::FieldDistortionUndeterminable& e) {
      throw InputError(std::string("--distortion: ") + e.what());
    }
  };
  const imaging::FieldDistortion none;
  size_t scan_index = 0;
  std::vector<artefacts::RegisteredScan> scans = ReadAndRegisterScans(
      layouts, pixel_mm, threads, progress,
      [&](const artefacts::RegisteredScan& scan, const std::vector<imaging::TileImage>& images) {
        append(scan_index, scan.name, images, scan.registration.pairs, scan.registration.positions,
               options.known ? *options.known : none);
        ++scan_index;
      });
  field->fit = fit(options.known ? &*options.known : nullptr);
  if (!options.known && options.rematch) {
    const std::vector<PairToRegisterAgain> first_again = again;
    // The second round: every overlap matched again from the field just found, each window of b warped to a's view
    // of it (imaging/overlap_correspondences.h): the two views of a point differ by the field's stretch, which the
    // first round's windows could not follow, and that biased the field's own-axis cubic terms (x^3 in dx, y^3 in
    // dy, the mosaic's scale) by about 0.0017 D^2 px on scangen (D px of radial field), 3-5 times their noise. The
    // tiles are read again (a scan's tiles stay in memory only while it is registered).
    const imaging::FieldDistortionFit first = field->fit;
    points = {}, again.clear(), kept.clear();
    int base = 0;
    Progress bar("matching the overlaps again through the field", static_cast<int>(scans.size()), progress);
    for (size_t s = 0; s < scans.size(); ++s) {
      const imaging::TileLayout layout = imaging::ReadTileLayout(layouts[s]);
      const std::vector<imaging::TileImage> images =
          imaging::ReadLayoutImages(layout, std::filesystem::path(layouts[s]).parent_path());
      // Each pair from the first round's undistorted offset (its rigid one where that round could not place it).
      std::vector<imaging::PairRegistration> pairs = scans[s].registration.pairs;
      for (size_t q = 0; q < pairs.size(); ++q) {
        const bool placed = std::none_of(first_again.begin(), first_again.end(),
                                         [&](const PairToRegisterAgain& r) { return r.scan == s && r.pair == q; });
        if (!pairs[q].accepted || !placed) continue;
        pairs[q].offset_px = first.positions_px[static_cast<size_t>(base + pairs[q].b)] -
                             first.positions_px[static_cast<size_t>(base + pairs[q].a)];
      }
      append(s, scans[s].name, images, pairs, scans[s].registration.positions, first.field);
      base += static_cast<int>(scans[s].encoder_mm.size());
      bar.Advance();
    }
    bar.Finish();
    field->fit = fit(nullptr);
  }
  field->identified = !options.known;

  // Every accepted pair's offset between the undistorted tiles: from the fit's positions where its correspondences
  // placed them (both tiles then in one group of the fit, whose positions chain consistently), else registered again
  // on the undistorted tiles. A pair the fit could not place keeps no rigid offset: a corner overlap sits where the
  // field is largest (2 sqrt(2) times the edges' for a radial one), and one biased step would be taken for stage
  // error, as would the jump between two groups of the fit each held at its rigid position.
  std::vector<std::vector<bool>> register_again(scans.size());
  for (size_t s = 0; s < scans.size(); ++s) register_again[s].assign(scans[s].registration.pairs.size(), false);
  for (const PairToRegisterAgain& r : again) register_again[r.scan][r.pair] = true;
  // Each scan's matched pairs in `points.matched` follow its accepted pairs in order.
  int base = 0;
  size_t next_matched = 0;
  const imaging::FieldDistortion& identified = field->fit.field;
  for (size_t s = 0; s < scans.size(); ++s) {
    artefacts::RegisteredScan& scan = scans[s];
    const auto k = static_cast<Eigen::Index>(identified.coefficients.size());
    scan.field_sensitivity.assign(scan.registration.pairs.size(), Eigen::Matrix<double, 2, Eigen::Dynamic>::Zero(2, k));
    scan.field_covariance_px2 =
        identified.covariance.size() > 0 ? identified.covariance : Eigen::MatrixXd(Eigen::MatrixXd::Zero(k, k));
    for (size_t q = 0; q < scan.registration.pairs.size(); ++q) {
      imaging::PairRegistration& pair = scan.registration.pairs[q];
      if (!pair.accepted) continue;
      const imaging::PairCorrespondences& overlap = points.matched[next_matched++];
      if (register_again[s][q]) {
        RegisterUndistortedPair(kept.at(base + pair.a), kept.at(base + pair.b), identified, pair);
        scan.field_sensitivity[q] = FieldSensitivityOverOverlap(identified, pair.offset_px);
      } else {
        pair.offset_px = field->fit.positions_px[static_cast<size_t>(base + pair.b)] -
                         field->fit.positions_px[static_cast<size_t>(base + pair.a)];
        scan.field_sensitivity[q] = FieldSensitivity(identified, overlap.a_px, overlap.b_px, overlap.kernel);
      }
    }
    // The positions chained from the undistorted offsets as the rigid registration chains its own.
    scan.registration.positions =
        imaging::SolveTilePositions(artefacts::NominalOffsetsPx(scan.encoder_mm, pixel_mm), scan.registration.pairs,
                                    imaging::RegistrationOptions{}.stage_sigma_px);
    base += static_cast<int>(scan.encoder_mm.size());
  }
  return scans;
}

}  // namespace fvm::workflows
