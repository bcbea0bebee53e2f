#include "workflows/stitch_distortion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/core.h>

namespace fvm::workflows {

void StitchDistortionOptions::Check() const {
  if (!known) imaging::FieldDistortionTermNames(order);  // throws outside 2..kMaxDistortionOrder
  if (known) known->Check();
  matching.Check();
  fit.Check();
}

namespace {

double MeanNcc(const std::vector<imaging::PairOverlapCorrelation>& pairs) {
  double sum = 0.0;
  int n = 0;
  for (const auto& p : pairs) {
    if (std::isfinite(p.correlation.ncc)) sum += p.correlation.ncc, ++n;
  }
  return n > 0 ? sum / n : NAN;
}

}  // namespace

StitchDistortionResult StitchWithoutDistortion(const StitchResult& rigid, const std::vector<imaging::TileImage>& images,
                                               const StitchDistortionOptions& options) {
  options.Check();
  if (images.size() != rigid.grid.size()) throw std::invalid_argument("StitchWithoutDistortion: one image per tile");
  const int width = static_cast<int>(images.front().cols()), height = static_cast<int>(images.front().rows());
  StitchDistortionResult out;
  out.identified = !options.known.has_value();
  imaging::FieldDistortionFitOptions fit_options = options.fit;
  fit_options.order = options.known ? options.known->order : options.order;
  fit_options.hold_stretch_terms = options.hold_stretch_terms;
  const imaging::PreparedTiles prepared = imaging::PrepareTilesForMatching(images, options.matching);
  // The field and the positions from the accepted pairs of `registration`, starting from its positions and `guess`.
  const auto identify = [&](const imaging::RegistrationResult& registration, imaging::FieldDistortion guess) {
    const imaging::TilePositions& positions = registration.positions;
    // The first tile of every group of tiles the accepted pairs join holds (the first tile is the frame), so does a
    // tile no pair reaches. Not `registered`: that is false also for a tile placed through pairs that fix one
    // direction, whose correspondences the field fit still takes (held at the rigid position, it would pull the
    // field and its neighbours by the stage's error along that direction).
    std::vector<bool> fixed(images.size(), false);
    for (size_t i = 0; i < images.size(); ++i) fixed[i] = positions.anchor[i] == static_cast<int>(i);
    std::vector<imaging::OverlapToMatch> overlaps;
    for (const imaging::PairRegistration& pair : registration.pairs) {
      if (pair.accepted) overlaps.push_back({pair.a, pair.b, pair.offset_px});
    }
    std::vector<Eigen::Vector2d> start = positions.positions_px;
    // Twice: the first round tracks a coarser grid of points (every other one along each axis) across the field's
    // whole pull; its field and positions put the second round's points within a fraction of a pixel, where each
    // is refined without the tracker, on the full grid. The tiles are prepared once for every round.
    for (int round = 0; round < 2; ++round) {
      imaging::CorrespondenceOptions matching = options.matching;
      if (round == 0) matching.grid_step_px *= 2;
      if (round > 0) matching.track = false;
      const std::vector<imaging::PairCorrespondences> matched =
          imaging::MatchPreparedOverlaps(prepared, overlaps, guess, matching);
      out.fit = imaging::FitFieldDistortion(matched, start, fixed, width, height, fit_options,
                                            options.known ? &*options.known : nullptr);
      guess = out.fit.field;
      start = out.fit.positions_px;
      for (imaging::OverlapToMatch& o : overlaps) {
        o.offset_px = start[static_cast<size_t>(o.b)] - start[static_cast<size_t>(o.a)];
      }
    }
  };
  const imaging::RegistrationResult* registration = &rigid.registration;
  const auto accepted = [](const imaging::RegistrationResult& r) {
    return static_cast<int>(std::count_if(r.pairs.begin(), r.pairs.end(), [](const auto& p) { return p.accepted; }));
  };
  try {
    identify(*registration, options.known ? *options.known : imaging::FieldDistortion{});
  } catch (const imaging::FieldDistortionUndeterminable& e) {
    const int rejected = static_cast<int>(rigid.registration.pairs.size()) - accepted(rigid.registration);
    if (rejected == 0) throw;
    // Say that the overlaps exist but did not register rigidly (a field strong enough to shear them does that).
    throw imaging::FieldDistortionUndeterminable(fmt::format(
        "{} ({} of the {} neighbour pairs did not register on the raw tiles: with a field as strong as the overlaps "
        "show, give the objective's field saved from a grid that registers with --distortion-file)",
        e.what(), rejected, rigid.registration.pairs.size()));
  }
  // Pairs the rigid registration rejected because the field shears their overlap (its displacement changes along
  // the band by more than the texture's grain: the raw overlaps do not match at any one offset) are what leave
  // tiles at their stage positions, pixels off. The grid is registered again on the tiles resampled without the
  // field found (edges clamped, not NaN: the registration wants finite pixels), and the field and the positions
  // identified again from every pair that registers there.
  imaging::RegistrationResult again;
  if (accepted(rigid.registration) < static_cast<int>(rigid.registration.pairs.size())) {
    again = imaging::RegisterTileGrid(imaging::UndistortTiles(images, out.fit.field, false), rigid.grid,
                                      options.registration);
    if (accepted(again) > accepted(rigid.registration)) {
      out.pairs_registered_undistorted = accepted(again) - accepted(rigid.registration);
      registration = &again;
      identify(*registration, out.fit.field);
    }
  }
  out.registration = *registration;
  const imaging::TilePositions& positions = registration->positions;
  for (const Eigen::Matrix2d& c : out.fit.position_covariance_px2) out.sigma_px.emplace_back(c.diagonal().cwiseSqrt());
  // Tiles the images do not place on both axes carry at least what the rigid solve says (the stage's uncertainty
  // along an axis no pair fixes).
  // A group of tiles the pairs do not join to the first tile (a hole, failed pairs) is fitted about its earliest tile,
  // held where the rigid solve put it: what the stage leaves of that tile against the first adds to each of them.
  for (size_t i = 0; i < images.size(); ++i) {
    const size_t anchor = static_cast<size_t>(positions.anchor[i]);
    if (anchor != 0 && anchor != i) {
      out.sigma_px[i] = (out.sigma_px[i].cwiseAbs2() + positions.sigma_px[anchor].cwiseAbs2()).cwiseSqrt();
    }
    if (!positions.registered[i]) out.sigma_px[i] = out.sigma_px[i].cwiseMax(positions.sigma_px[i]);
  }
  out.undistorted = imaging::UndistortTiles(images, out.fit.field);
  out.overlap_ncc = imaging::NeighbourOverlapNcc(out.undistorted, rigid.grid, out.fit.positions_px);
  out.mean_overlap_ncc_before = rigid.mean_overlap_ncc;
  out.mean_overlap_ncc_after = MeanNcc(out.overlap_ncc);
  return out;
}

}  // namespace fvm::workflows
