#include "stage/scan_correction.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <limits>

#include "core/input_error.h"
#include "stage/identification.h"

namespace fvm::stage {
namespace {

// The axes whose coordinate some term of the model takes: beyond their travel the polynomials extrapolate.
std::array<bool, 3> AxesWithTerms(const ParameterLayout& layout) {
  std::array<bool, 3> axes{};
  for (const ParameterLayout::Coefficient& c : layout.coefficients()) {
    axes[static_cast<std::size_t>(layout.chain().ArgumentAxis(c.term))] = true;
  }
  return axes;
}

}  // namespace

std::vector<std::size_t> PointsOutsideTravel(const ParameterLayout& layout, const std::vector<Eigen::Vector3d>& points,
                                             const Eigen::Vector3d& origin_mm) {
  const std::array<bool, 3> axes = AxesWithTerms(layout);
  std::vector<std::size_t> outside;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    const Eigen::Vector3d q = points[i] + origin_mm;
    for (int k = 0; k < 3; ++k) {
      const Travel& t = layout.travel()[static_cast<std::size_t>(k)];
      if (axes[static_cast<std::size_t>(k)] && (q[k] < t.min || q[k] > t.max)) {
        outside.push_back(i);
        break;
      }
    }
  }
  return outside;
}

ScanCorrector::ScanCorrector(const Calibration& calibration, const ScanCorrectionOptions& options,
                             const std::vector<Eigen::Vector3d>& file_points)
    : calibration_(calibration), options_(options), all_(calibration.layout.coefficients().size()) {
  calibration.layout.Expand(calibration.values.data(), all_.data());
  if (!options.first_tile_frame) return;
  if (std::none_of(file_points.begin(), file_points.end(), [](const Eigen::Vector3d& p) { return p.allFinite(); })) {
    throw InputError("no valid point, so no first tile to start the stitched frame at");
  }
  first_tile_.emplace(calibration, *options.first_tile_frame, FirstTile(file_points, options.origin_mm));
}

CorrectedPoint ScanCorrector::Correct(const Eigen::Vector3d& file_point) const {
  const Eigen::Vector3d q = file_point + options_.origin_mm;
  CorrectedPoint out;
  if (first_tile_) {
    out = first_tile_->Correct(q);
  } else {
    // stage::Correct without its allocations: the 3 x 21 term Jacobian times the sparse term derivative, then
    // J Cov J^T.
    const ParameterLayout& layout = calibration_.layout;
    double e[kNumErrorTerms];
    layout.TermValues(all_.data(), q, e);
    const Eigen::Matrix<double, 3, kNumErrorTerms> tj =
        TermJacobian(layout.chain(), e, q, &out.position, layout.AxesWithErrors());
    const Eigen::Index n = layout.NumFree();
    if (calibration_.covariance.rows() == n) {
      Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxCoefficients> j = Eigen::MatrixXd::Zero(3, n);
      for (const ParameterLayout::TermDerivativeEntry& d : layout.TermDerivativeEntries(q)) {
        j.col(d.slot) += tj.col(d.term) * d.value;
      }
      const Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxCoefficients> jc = j * calibration_.covariance;
      out.covariance = jc * j.transpose();
    }
    out.covariance += calibration_.unmodelled_mm.cwiseAbs2().asDiagonal();
  }
  out.position -= options_.origin_mm;
  return out;
}

Eigen::Vector3d ScanCorrector::Position(const Eigen::Vector3d& file_point) const {
  const Eigen::Vector3d q = file_point + options_.origin_mm;
  if (first_tile_) return (*first_tile_)(q) - options_.origin_mm;
  double e[kNumErrorTerms];
  calibration_.layout.TermValues(all_.data(), q, e);
  return ChainForward(calibration_.layout.chain(), e, q) - options_.origin_mm;
}

ScanCorrectionSummary CorrectScanInPlace(const ScanCorrector& corrector, std::vector<Eigen::Vector3d>& points,
                                         std::vector<Eigen::Vector3d>* u, int threads) {
  if (u) u->assign(points.size(), Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  const auto join = [](ScanCorrectionSummary a, const ScanCorrectionSummary& b) {
    a.corrected += b.corrected;
    a.invalid += b.invalid;
    a.largest_shift_mm = std::max(a.largest_shift_mm, b.largest_shift_mm);
    return a;
  };
  // Each point is independent and the result of each is the same whatever thread computes it: same bits for any
  // thread count.
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  return arena.execute([&] { return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points.size(), 4096), ScanCorrectionSummary{},
      [&](const tbb::blocked_range<std::size_t>& range, ScanCorrectionSummary s) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          Eigen::Vector3d& p = points[i];
          if (!p.allFinite()) {
            ++s.invalid;
            continue;
          }
          Eigen::Vector3d moved;
          if (u) {
            const CorrectedPoint c = corrector.Correct(p);
            moved = c.position;
            (*u)[i] = c.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
          } else {
            moved = corrector.Position(p);
          }
          s.largest_shift_mm = std::max(s.largest_shift_mm, (moved - p).norm());
          p = moved;
          ++s.corrected;
        }
        return s;
      },
      join); });
}

}  // namespace fvm::stage
