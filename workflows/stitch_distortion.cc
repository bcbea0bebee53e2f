#include "workflows/stitch_distortion.h"

#include <cmath>
#include <stdexcept>

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
  const imaging::TilePositions& positions = rigid.registration.positions;
  // Tiles the rigid solve left at their stage positions hold there; so does the first tile (the frame).
  std::vector<bool> fixed(images.size(), false);
  fixed[0] = true;
  for (size_t i = 0; i < images.size(); ++i) {
    if (!positions.registered[i]) fixed[i] = true;
  }
  std::vector<imaging::OverlapToMatch> overlaps;
  for (const imaging::PairRegistration& pair : rigid.registration.pairs) {
    if (pair.accepted) overlaps.push_back({pair.a, pair.b, pair.offset_px});
  }
  StitchDistortionResult out;
  out.identified = !options.known.has_value();
  imaging::FieldDistortion guess;  // the identity
  if (options.known) guess = *options.known;
  std::vector<Eigen::Vector2d> start = positions.positions_px;
  imaging::FieldDistortionFitOptions fit_options = options.fit;
  fit_options.order = options.known ? options.known->order : options.order;
  fit_options.hold_stretch_terms = options.hold_stretch_terms;
  // Twice: the first round tracks a coarser grid of points (every other one along each axis) across the field's
  // whole pull; its field and positions put the second round's points within a fraction of a pixel, where each
  // is refined without the tracker, on the full grid. The tiles are prepared once for both.
  const imaging::PreparedTiles prepared = imaging::PrepareTilesForMatching(images, options.matching);
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
  for (const Eigen::Matrix2d& c : out.fit.position_covariance_px2) out.sigma_px.emplace_back(c.diagonal().cwiseSqrt());
  // Tiles at their stage positions carry the stage's uncertainty, as the rigid solve says.
  for (size_t i = 0; i < images.size(); ++i) {
    if (!positions.registered[i]) out.sigma_px[i] = positions.sigma_px[i];
  }
  out.undistorted = imaging::UndistortTiles(images, out.fit.field);
  out.overlap_ncc = imaging::NeighbourOverlapNcc(out.undistorted, rigid.grid, out.fit.positions_px);
  out.mean_overlap_ncc_before = rigid.mean_overlap_ncc;
  out.mean_overlap_ncc_after = MeanNcc(out.overlap_ncc);
  return out;
}

}  // namespace fvm::workflows
