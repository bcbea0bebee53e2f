#include "stage/unexplained_remainder.h"

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <Eigen/QR>
#include <boost/math/distributions/fisher_f.hpp>
#include <algorithm>
#include <cmath>

#include "core/dense_decomposition.h"
#include "stage/discrepancy_scoring.h"
#include "stage/residual_findings.h"
#include "stage/validation.h"

namespace fvm::stage {
namespace {

std::string Likeliest(const std::vector<std::string>& names) {
  const std::vector<std::string> also(names.begin() + 1, names.end());
  return fmt::format("the likeliest cause is the refused {}{}, which these data cannot show on its own (see the notes)",
                     names.front(), also.empty() ? "" : fmt::format(" (also refused: {})", fmt::join(also, ", ")));
}

}  // namespace

Remainder JudgeRemainder(const std::vector<Eigen::Vector3d>& residuals, int num_free, const MeasurementSet& identify,
                         const std::vector<std::string>& refused_now, const std::vector<std::string>& ever_refused,
                         const ResidualSummary& validation) {
  Remainder out;
  const double noise_mm = NeighbourNoise(residuals, identify);
  double squares = 0;
  for (const Eigen::Vector3d& r : residuals) squares += r.squaredNorm();
  const double dof = std::max(1.0, 3.0 * static_cast<double>(residuals.size()) - num_free);
  const double left_mm = std::sqrt(squares / dof);
  const bool above_noise = noise_mm > 0 && left_mm > 2.0 * noise_mm;
  if (!refused_now.empty() || above_noise) {
    out.fits_noise = false;
    out.unexplained = fmt::format(
        "unexplained: {:.2f} um rms per coordinate remains in the identification residuals ({:.1f} times the noise "
        "between neighbouring calottes, {:.2f} um){}; {}. No other effect is named for it",
        left_mm * 1e3, noise_mm > 0 ? left_mm / noise_mm : 0.0, noise_mm * 1e3,
        refused_now.empty() ? "" : ", and a candidate the held-out placements refused still explains part of it significantly",
        refused_now.empty() ? "it is a shape neither the model nor the listed effects take: try a higher model order"
                            : Likeliest(refused_now));
    return out;
  }
  if (ever_refused.empty()) return out;
  // A candidate refused earlier left its pattern where the identification data cannot see it any more (later
  // effects took it there) but the held-out placements still may.
  out.fits_noise = false;
  const ResidualSummary fit = Summarize(residuals);
  if (validation.count > 0 && validation.mean_mm > 2.0 * fit.mean_mm) {
    out.unexplained = fmt::format(
        "unexplained: the held-out placements keep {:.2f} um mean residual against {:.2f} um for the identification "
        "placements; {}. The turn of the held-out frames is not tested: it would take the pattern a refused candidate "
        "leaves on placements measured in order",
        validation.mean_mm * 1e3, fit.mean_mm * 1e3, Likeliest(ever_refused));
  }
  return out;
}

std::optional<TurnsRefused> DriftInsteadOfTurns(const Calibration& calibration, const MeasurementSet& validate,
                                                StitchedFrame frame, const std::vector<Eigen::Vector3d>& turned_residuals,
                                                const TurnTestOutcome& turns, const ResidualSummary& validation,
                                                const ResidualSummary& fit, double alpha) {
  if (validate.t_s.size() != validate.observations.size() || validate.observations.empty()) return std::nullopt;
  const Eigen::VectorXd r = Stack(Validate(&calibration, validate.observations, validate.anchors, frame).residuals);
  // The alternative: three drift rates and the six linear terms of the xy arm from each first tile, common to
  // every placement (what a model whose linear terms took part of a drift gets wrong on the held-out bars).
  Eigen::MatrixXd alternative(r.size(), 9);
  alternative.leftCols(3) = DriftColumns(validate, 0.0);
  alternative.rightCols(6).setZero();
  for (size_t i = 0; i < validate.observations.size(); ++i) {
    const Observation& o = validate.observations[i];
    const Eigen::Vector3d arm = o.command - validate.anchors.at(static_cast<size_t>(o.group));
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 2; ++k) alternative(3 * static_cast<Eigen::Index>(i) + c, 3 + 2 * c + k) = arm[k];
    }
  }
  const Eigen::VectorXd left =
      r - alternative * Decompose<Eigen::ColPivHouseholderQR<Eigen::MatrixXd>>(alternative, "the remainder: drift and turn").solve(r);
  const Eigen::MatrixXd linear = alternative.rightCols(6);
  const Eigen::VectorXd left_linear =
      r - linear * Decompose<Eigen::ColPivHouseholderQR<Eigen::MatrixXd>>(linear, "the remainder: turn").solve(r);
  const double m = static_cast<double>(r.size());
  const double drift_rms_mm = std::sqrt(left.squaredNorm() / m), turn_rms_mm = std::sqrt(Stack(turned_residuals).squaredNorm() / m);
  if (drift_rms_mm > turn_rms_mm || m <= 9.0 || !(left.squaredNorm() > 0)) return std::nullopt;
  // And the drift must be there: its three rates significant beyond the linear terms (F-test at `alpha`); a turn
  // common to the placements is the linear terms' rotation part, not a drift.
  const double f = ((left_linear.squaredNorm() - left.squaredNorm()) / 3.0) / (left.squaredNorm() / (m - 9.0));
  const double p = f > 0 ? boost::math::cdf(boost::math::complement(boost::math::fisher_f_distribution<double>(3.0, m - 9.0), f)) : 1.0;
  if (!(p < alpha)) return std::nullopt;
  TurnsRefused out;
  out.note = fmt::format(
      "step {}: frame_rotation: the held-out placements turn about their first tiles beyond their noise (p = {:.2g}), "
      "but a drift in measurement time with the model's linear terms along the bars, common to all of them, leaves no "
      "more of their residuals ({:.2f} um rms per coordinate, against {:.2f} um with a turn of each placement): their "
      "calottes are measured in order, so a drift grows from each first tile as a turn does, and the identification's "
      "linear terms took part of it; not named",
      turns.step, turns.p_value, drift_rms_mm * 1e3, turn_rms_mm * 1e3);
  out.unexplained = fmt::format(
      "unexplained: the held-out placements keep {:.2f} um mean residual against {:.2f} um for the identification "
      "placements; the likeliest cause is {}, which bars measured in order cannot tell from the model's terms that "
      "grow along them: measuring every other placement backwards shows a drift at the shared start",
      validation.mean_mm * 1e3, fit.mean_mm * 1e3,
      turns.drift_corrected ? "what the thermal_drift correction left (its rates trade off against those terms)"
                            : "a thermal_drift the identification data do not show");
  return out;
}

}  // namespace fvm::stage
