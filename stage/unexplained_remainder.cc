#include "stage/unexplained_remainder.h"

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "stage/residual_findings.h"

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

}  // namespace fvm::stage
