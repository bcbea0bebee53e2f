#include "imaging/tile_pair_registration.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/dense_decomposition.h"
#include "imaging/registration_information.h"
#include "imaging/subpixel_refinement.h"
#include "imaging/tile_prefilter.h"
#include "imaging/translation_candidates.h"

namespace fvm::imaging {

using namespace detail;

namespace {

MatchScale Scale(const RegistrationOptions& options) {
  return {options.match_highpass_sigma_px, options.match_sigma_px};
}

}  // namespace

void RegistrationOptions::Check() const {
  if (!(min_quality >= -1.0 && min_quality <= 1.0)) throw std::invalid_argument("min_quality must be in [-1, 1]");
  if (!(max_correction > 0.0 && max_correction <= 0.5)) throw std::invalid_argument("max_correction: (0, 0.5]");
  if (!(search_fraction > 0.0 && search_fraction <= 0.5)) throw std::invalid_argument("search_fraction: (0, 0.5]");
  if (candidate_peaks < 1) throw std::invalid_argument("candidate_peaks must be >= 1");
  if (!(highpass_sigma_px >= 0.0)) throw std::invalid_argument("highpass_sigma_px must be >= 0");
  if (!(wide_search_fraction >= search_fraction && wide_search_fraction <= 0.5)) {
    throw std::invalid_argument("wide_search_fraction: [search_fraction, 0.5]");
  }
  if (!(match_sigma_px >= 0.0)) throw std::invalid_argument("match_sigma_px must be >= 0");
  if (!(match_highpass_sigma_px >= 0.0)) throw std::invalid_argument("match_highpass_sigma_px must be >= 0");
  if (!(ambiguous_ncc >= 0.0)) throw std::invalid_argument("ambiguous_ncc must be >= 0");
  if (!(stage_sigma_px > 0.0)) throw std::invalid_argument("stage_sigma_px must be positive");
}

namespace {

// Whole frames (cropped to a common size): the correlation finds the offset modulo the frame size; the
// representative nearest the nominal offset is taken. `response` gets the correlation peak.
Eigen::Vector2d WholeFrameShift(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                                double highpass_sigma_px, double& response) {
  const cv::Rect common(0, 0, static_cast<int>(std::min(a.cols(), b.cols())), static_cast<int>(std::min(a.rows(), b.rows())));
  const bool logarithm = MatchingDomain(View(a)(common), View(b)(common));
  const auto [e, peak] = PhaseShift(HighPass(View(a)(common), highpass_sigma_px, logarithm).value,
                                    HighPass(View(b)(common), highpass_sigma_px, logarithm).value);
  response = peak;
  Eigen::Vector2d offset = e;
  offset.x() += common.width * std::round((nominal_px.x() - e.x()) / common.width);
  offset.y() += common.height * std::round((nominal_px.y() - e.y()) / common.height);
  return offset;
}

// From a whole- or sub-pixel `offset` of b in a's frame: refines it on the overlap it implies, measures the
// quality and the information there, and decides. `searched`: the offset is a candidate of the widened search,
// which may lie a pixel or two off on broad blobs (the refinement may crop again, up to three times, and an
// offset it could not refine claims a pixel's variance less); otherwise it is the nominal overlap's
// phase-correlation peak, refined once on one crop (`reuse`, when given, is the crop at its whole pixel).
// `clear_peak_px` > 0: the overlap NCC over the whole plausible range had one clear peak, located to this (px).
// Returns whether the sub-pixel refinement settled (false also when it was not asked for).
bool RefineAndMeasure(const TileImage& a, const TileImage& b, Eigen::Vector2d offset,
                      const RegistrationOptions& options, bool searched, std::optional<Overlap> reuse,
                      PairRegistration& pair, double clear_peak_px = 0.0) {
  const Eigen::Vector2d nominal_px = pair.nominal_px;
  const int crops = searched ? 3 : 1;
  // Crop again where the images really overlap, to the whole pixel: the shift left to refine is at most half a
  // pixel, so the refinement and the quality lose only a few pixels of a narrow overlap to their margins.
  // A refinement that ends more than half a pixel from its start crops again there and refines once more (a
  // candidate on broad blobs can be a pixel or two off): the shift left to refine stays below a pixel, where thin
  // overlaps keep their interior.
  Eigen::Vector2i whole;
  std::optional<Overlap> overlap;
  Eigen::Vector2d e;
  bool settled = !options.refine;  // the peak alone claims nothing more when asked for nothing more
  for (int crop = 0; crop < crops; ++crop) {
  whole = offset.array().round().cast<int>();
  overlap = crop == 0 && reuse ? std::move(reuse) : CropOverlap(a, b, whole, options.highpass_sigma_px);
  if (!overlap) {
    pair.rejection = "the measured overlap is narrower than 8 px";
    return false;
  }
  e = offset - whole.cast<double>();
  if (options.refine) {
    // Coarse to fine: the phase-correlation peak can be a pixel off, outside the basin of Gauss-Newton on fine
    // texture (a quarter period); blurred crops widen the basin, then the full-resolution pass sets the sub-pixel.
    Eigen::Vector2d refined = e;
    // The coarse pass only needs to land in the fine pass' basin, so its not settling is no verdict (the fine pass
    // starts from the correlation's estimate then); the fine one stops well below the noise, and a fine pass
    // that runs out of iterations still moving rejects the pair: its shift is not a minimum of the mismatch.
    Eigen::Vector2d coarse = e;
    const Refinement coarse_status = RefineShift(Blur(overlap->a, 2.5), Blur(overlap->b, 2.5), 0.05, coarse);
    if (coarse_status == Refinement::kSettled) refined = coarse;
    Eigen::Vector2d last_step = Eigen::Vector2d::Zero(), last_estimate = refined;
    const Refinement fine = coarse_status == Refinement::kSettled || coarse_status == Refinement::kNotSettled
                                ? RefineShift(overlap->a, overlap->b, 2e-3, refined, &last_step, &last_estimate)
                                : coarse_status;
    settled = fine == Refinement::kSettled;
    if (fine == Refinement::kSettled) e = refined;
    if (fine == Refinement::kNotSettled) {
      // Out of iterations while still moving. The pair stands only if the last step is below half a standard
      // deviation of the offset it will claim (in the directions its texture determines: along machining marks
      // the steps follow the noise, and the information leaves that direction to the stage); otherwise the
      // offset is no minimum within its own precision, and the pair is rejected.
      const Alignment at = MeasureAlignment(overlap->a, overlap->b, last_estimate, 0.0);
      const double moving = std::sqrt(last_step.dot(at.information * last_step));
      if (moving <= 0.5) {
        e = last_estimate;
        settled = true;
      } else {
        pair.rejection = "the sub-pixel refinement did not settle (its last step, " + std::to_string(last_step.norm()) +
                         " px, is " + std::to_string(moving) + " standard deviations of the offset)";
      }
    }
    // Otherwise (no room, no texture, wandered) the phase-correlation estimate stands, and the quality and the
    // texture test below decide.
  }
  offset = whole.cast<double>() + e;
  if (!pair.rejection.empty() || (offset.array().round().cast<int>() == whole.array()).all()) break;
  }
  const Alignment alignment = MeasureAlignment(overlap->a, overlap->b, e, options.match_sigma_px);
  pair.quality = MatchQuality(a, b, offset.array().round().cast<int>(), Scale(options));
  pair.information = alignment.information;
  if (searched && !settled && !pair.information.isZero()) {
    // Not refined (no room, wandered): the offset is a whole-pixel candidate, or the correlation's peak, which
    // on broad blobs lies up to a pixel off. Its information says what the overlap could tell, not what this
    // estimate holds: add a pixel's variance (0.5 px standard deviation) in every direction it claims.
    const auto directions = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>>(pair.information, "a tile pair's information");
    Eigen::Matrix2d information = Eigen::Matrix2d::Zero();
    for (int k = 0; k < 2; ++k) {
      const double lambda = directions.eigenvalues()(k);
      const Eigen::Vector2d u = directions.eigenvectors().col(k);
      if (lambda > 1e-9 * directions.eigenvalues()(1)) information += 1.0 / (1.0 / lambda + 0.25) * u * u.transpose();
    }
    pair.information = information;
  }
  pair.offset_px = offset;
  {
    // Along a direction the overlap does not determine (machining marks), the offset is wherever the search ended
    // on the ridge, up to the window's width from the truth; the nominal says as much, and no tilt of the rank-one
    // information by noise can then carry a wild value into the solve.
    const auto directions = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>>(pair.information, "a tile pair's information");
    if (clear_peak_px > 0.0) {
      // Unless the overlap's NCC over the whole plausible range had one clear peak (WideCandidates): then the
      // images fix the offset along every direction, to clear_peak_px (the standard uncertainty), where the gradients of a noisy overlap stood out of their noise along one direction
      // only (the real strip's pen strokes and grid lines). (Half a pixel instead put a pair of one grey level of
      // texture 8 of them from its truth.)
      for (int k = 0; k < 2; ++k) {
        if (directions.eigenvalues()(k) > 1e-9 * directions.eigenvalues()(1)) continue;
        const Eigen::Vector2d u = directions.eigenvectors().col(k);
        pair.information += 1.0 / (clear_peak_px * clear_peak_px) * u * u.transpose();
      }
    } else if (directions.eigenvalues()(1) > 0.0 && directions.eigenvalues()(0) <= 1e-9 * directions.eigenvalues()(1)) {
      const Eigen::Vector2d u = directions.eigenvectors().col(1);
      const Eigen::Vector2d projected = nominal_px + u * u.dot(pair.offset_px - nominal_px);
      pair.offset_px = projected;
    }
  }
  if (pair.rejection.empty() && !(pair.quality >= options.min_quality)) {
    pair.rejection = "quality " + std::to_string(pair.quality) + " is below min_quality " + std::to_string(options.min_quality);
  }
  if (pair.rejection.empty() && pair.information.isZero()) {
    pair.rejection = "the overlap has no texture that stands out of the noise in any direction";
  }
  pair.accepted = pair.rejection.empty();
  return settled && options.refine;
}

}  // namespace

namespace {

// RegisterPair; `clear_peak_px` as for RefineAndMeasure.
PairRegistration RegisterNominal(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                                 const RegistrationOptions& options, double clear_peak_px) {
  PairRegistration pair;
  pair.nominal_px = nominal_px;
  const Eigen::Vector2i nominal_whole = nominal_px.array().round().cast<int>();
  std::optional<Overlap> nominal = CropOverlap(a, b, nominal_whole, options.highpass_sigma_px, false);
  if (!nominal) {
    pair.rejection = "the nominal overlap is narrower than 8 px";
    return pair;
  }
  const double limit = options.max_correction * std::min(nominal->in_a.width, nominal->in_a.height);
  pair.search_px = Eigen::Vector2d::Constant(limit);
  const int nominal_area = nominal->in_a.area();

  Eigen::Vector2d offset;
  if (options.crop_to_overlap) {
    const auto [e, response] = PhaseShift(nominal->a.value, nominal->b.value);
    pair.response = response;
    offset = nominal_whole.cast<double>() + e;
  } else {
    offset = WholeFrameShift(a, b, nominal_px, options.highpass_sigma_px, pair.response);
  }
  if ((offset - nominal_px).cwiseAbs().maxCoeff() > limit) {
    pair.rejection = "the correlation's shift is farther from the nominal one than max_correction allows";
    return pair;
  }
  // The nominal crop serves again when the peak keeps its whole pixel and the overlap is not thin (a thin one is
  // cropped again, mirrored out for the refinement's margins).
  const bool thin = std::min(nominal->in_a.width, nominal->in_a.height) < kThinOverlapPx;
  std::optional<Overlap> reuse;
  if (!thin && offset.array().round().cast<int>().matrix() == nominal_whole) reuse = std::move(nominal);
  RefineAndMeasure(a, b, offset, options, false, std::move(reuse), pair, clear_peak_px);
  TranslationCandidate single;
  single.offset_px = pair.offset_px;
  single.peak = pair.response;
  single.ncc = pair.quality;
  single.overlap_px = nominal_area;
  pair.candidates.push_back(single);
  return pair;
}

}  // namespace

PairRegistration RegisterPair(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                              const RegistrationOptions& options) {
  options.Check();
  return RegisterNominal(a, b, nominal_px, options, 0.0);
}

PairRegistration RegisterPairOverRange(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                                       const Eigen::Vector2d& range_px, const RegistrationOptions& options) {
  options.Check();
  if (!(range_px.minCoeff() >= 0.0)) throw std::invalid_argument("RegisterPairOverRange: the range must be >= 0");
  const WideSearch wide = WideCandidates(a, b, nominal_px, range_px, options.candidate_peaks, Scale(options),
                                         options.ambiguous_ncc);
  // The landscape judges where its best match passes as a pair would (the height maps' roughness, say, correlates
  // in the first pass' high-passed band only): no overlap of a quarter of the nominal one anywhere, or none that
  // matches, and the nominal overlap decides alone.
  const bool judges = !wide.candidates.empty() && wide.candidates.front().ncc >= options.min_quality;
  if (!judges) return RegisterNominal(a, b, nominal_px, options, 0.0);
  const TranslationCandidate& best = wide.candidates.front();
  // Tiles the stage moved apart that match one on the other, better than anywhere in the range, show no motion:
  // the same image twice (a frozen camera, a copied file). (Machining marks along the step match one on the other
  // as well as at the step, and no better: their ridge leaves the axis along them to the stage.)
  if (nominal_px.cwiseAbs().maxCoeff() >= kMinOverlapPx && wide.unmoved_ncc >= options.min_quality &&
      wide.unmoved_ncc > best.ncc + options.ambiguous_ncc) {
    PairRegistration pair;
    pair.nominal_px = nominal_px;
    pair.search_px = range_px;
    char text[240];
    std::snprintf(text, sizeof text,
                  "the tiles match where the stage did not move them (offset 0, NCC %.3f) better than anywhere in the "
                  "plausible range (best NCC %.3f): the same image at two stage positions",
                  wide.unmoved_ncc, best.ncc);
    pair.unmoved = true;
    pair.rejection = text;
    pair.candidates = wide.candidates;
    return pair;
  }
  // The range's best match, refined, where it is one clear peak: the nominal overlap's own peak of a repeating
  // pattern matched its lines one period off, or the true step lay farther from the nominal one than its overlap
  // reaches. Half the landscape's pixel is its uncertainty along what the refinement leaves undetermined (the
  // level's pixel it starts from lies within half of one of the peak; a whole pixel put a pair of the real strip
  // 5 px off under the stage's prior).
  const bool clear = !wide.ambiguous && wide.sharp;
  if (clear) {
    PairRegistration searched;
    searched.nominal_px = nominal_px;
    searched.search_px = range_px;
    searched.searched = true;
    searched.candidates = wide.candidates;
    searched.response = best.peak;
    const double level_px = 0.5 * wide.scale;
    const bool settled = RefineAndMeasure(a, b, best.offset_px, options, true, std::nullopt, searched, level_px);
    const bool to_level = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>>(searched.information,
                                                                                    "a tile pair's information")
                                  .eigenvalues()(0) <=
                          (1.0 + 1e-9) / (level_px * level_px);
    if ((!settled || to_level) && options.refine && wide.scale > 1) {
      // The refinement wandered off the level's pixel (on the real strip, tiles turned against each other by a
      // few tenths of a degree: no one shift fits their whole overlap), or the gradients left a direction to the
      // level's pixel: the peak is sought again at full resolution near it, and refined from there; where it
      // wanders again, that peak stands, to half a pixel.
      PairRegistration polished = searched;
      polished.rejection.clear();
      const Eigen::Vector2d peak =
          PolishPeak(a, b, best.offset_px.array().round().cast<int>(), wide.scale / 2 + 1, Scale(options));
      RefineAndMeasure(a, b, peak, options, true, std::nullopt, polished, 0.5);
      searched = polished;
    }
    if (searched.accepted) return searched;
  }
  // Otherwise (a ridge or a repeat, which places the match no better than the nominal overlap does, or a clear
  // peak the refinement rejected) the nominal overlap's phase correlation, as the first pass always did.
  PairRegistration pair = RegisterNominal(a, b, nominal_px, options, 0.0);
  pair.ambiguous = wide.ambiguous;
  pair.candidates.insert(pair.candidates.end(), wide.candidates.begin(), wide.candidates.end());
  return pair;
}

PairRegistration SearchPair(const TileImage& a, const TileImage& b, const Eigen::Vector2d& nominal_px,
                            const Eigen::Vector2d& search_px, const RegistrationOptions& options) {
  options.Check();
  if (!(search_px.minCoeff() >= 0.0)) throw std::invalid_argument("SearchPair: the search window must be >= 0");
  PairRegistration pair;
  pair.nominal_px = nominal_px;
  pair.search_px = search_px;
  pair.searched = true;
  const Eigen::Vector2i nominal_whole = nominal_px.array().round().cast<int>();
  const cv::Rect nominal_overlap =
      cv::Rect(0, 0, static_cast<int>(a.cols()), static_cast<int>(a.rows())) &
      cv::Rect(nominal_whole.x(), nominal_whole.y(), static_cast<int>(b.cols()), static_cast<int>(b.rows()));
  if (nominal_overlap.width < kMinOverlapPx || nominal_overlap.height < kMinOverlapPx) {
    pair.rejection = "the nominal overlap is narrower than 8 px";
    return pair;
  }
  Eigen::Vector2d offset;
  if (options.crop_to_overlap) {
    pair.candidates =
        SearchCandidates(a, b, nominal_px, search_px, options.candidate_peaks, options.highpass_sigma_px,
                         Scale(options), options.ambiguous_ncc, pair.ambiguous);
    if (pair.candidates.empty()) {
      pair.rejection = "no correlation peak implies an overlap within the search window";
      return pair;
    }
    pair.response = pair.candidates.front().peak;
    offset = pair.candidates.front().offset_px;
  } else {
    offset = WholeFrameShift(a, b, nominal_px, options.highpass_sigma_px, pair.response);
    if (((offset - nominal_px).cwiseAbs() - search_px).maxCoeff() > 0.0) {
      pair.rejection = "the correlation's shift lies outside the search window";
      return pair;
    }
  }
  RefineAndMeasure(a, b, offset, options, true, std::nullopt, pair);
  return pair;
}

}  // namespace fvm::imaging
