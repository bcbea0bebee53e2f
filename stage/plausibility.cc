#include "stage/plausibility.h"

#include <fmt/core.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "core/dense_decomposition.h"
#include "stage/calibration.h"
#include "stage/error_terms.h"

namespace fvm::stage {
namespace {

constexpr double kDefaultErrorPerLength = 1e-3;  // 1 mm per metre
constexpr int kSamples = 61;
// Angles are held to ten times the bound over the longest travel (10 mrad by default, the truth files' limit): they
// act through lever arms the travel does not hold (tool offsets, the tracker's distance), and published test
// functions reach 1.2 mrad on a 290 mm piece ([Lorente 2021] Table 4: yRx).
constexpr double kAngleLeverFactor = 10.0;                     // along each axis' travel, as the term tables sample it

double LongestTravel(const ParameterLayout& layout) {
  double longest = 0;
  for (const Travel& t : layout.travel()) longest = std::max(longest, t.max - t.min);
  return longest;
}

std::string Length(double mm) {
  return std::abs(mm) >= 1.0 ? fmt::format("{:.4g} mm", mm) : fmt::format("{:.4g} um", mm * 1e3);
}

std::string Angle(double rad) {
  return std::abs(rad) >= 1e-3 ? fmt::format("{:.4g} mrad", rad * 1e3) : fmt::format("{:.4g} urad", rad * 1e6);
}

std::string BoundText(double max_error_mm, double longest_mm, bool is_default) {
  return is_default ? fmt::format("{}: 1 mm per metre of the longest travel, {:.4g} mm", Length(max_error_mm), longest_mm)
                    : Length(max_error_mm);
}

// What a term far beyond any machine's error says about the data.
std::string Diagnosis(const ErrorTerm& term, const TermExcess& e) {
  const char axis = static_cast<char>(std::toupper(AxisLetter(term.axis)));
  const bool positioning = term.kind == ErrorKind::kTranslation && term.component == static_cast<int>(term.axis);
  if (positioning && std::abs(e.slope + 2.0) < 0.2) {
    return fmt::format("the readings run opposite to the machine's {} axis (a scale of {:.3f}): are the instrument's "
                       "axes mirrored (a left-handed frame, or one coordinate column with the wrong sign)?",
                       axis, 1.0 + e.slope);
  }
  if (positioning && std::abs(e.slope + 1.0) < 0.2) {
    return fmt::format("the readings hardly move when the {} axis does (a scale of {:.3g}): are they in metres instead "
                       "of millimetres, or is a coordinate column constant or repeated?",
                       axis, 1.0 + e.slope);
  }
  if (positioning && e.slope > 10.0) {
    return fmt::format("the readings move {:.4g} times as far as the {} axis: are they in micrometres instead of "
                       "millimetres?",
                       1.0 + e.slope, axis);
  }
  return "check the units (mm, rad), that no two coordinate columns are swapped or mirrored, the tool offset, and "
         "that each reading belongs to its commanded point";
}

}  // namespace

double DefaultMaxErrorMm(const ParameterLayout& layout) { return kDefaultErrorPerLength * LongestTravel(layout); }

TermExcess LargestExcess(const Calibration& cal, double max_error_mm) {
  const ParameterLayout& layout = cal.layout;
  const double longest = std::max(LongestTravel(layout), 1e-9);
  std::vector<double> all(layout.coefficients().size(), 0.0);
  layout.Expand(cal.values.data(), all.data());
  Eigen::Vector3d origin;
  for (int k = 0; k < 3; ++k) origin[k] = layout.travel()[static_cast<size_t>(k)].min;
  TermExcess worst;
  double worst_ratio = -1.0;
  for (int t = 0; t < kNumErrorTerms; ++t) {
    if (!layout.term(t).present) continue;
    const ErrorTerm& term = GetErrorTerm(t);
    const int axis = static_cast<int>(layout.chain().ArgumentAxis(t));
    const Travel travel = layout.travel()[static_cast<size_t>(axis)];
    const bool squareness = term.kind == ErrorKind::kSquareness;
    const double limit = term.kind == ErrorKind::kTranslation ? max_error_mm : kAngleLeverFactor * max_error_mm / longest;
    double e0[kNumErrorTerms];
    layout.TermValues(all.data(), origin, e0);
    double deviation = 0;
    for (int i = 0; i < kSamples; ++i) {
      Eigen::Vector3d q = origin;
      q[axis] = travel.min + (travel.max - travel.min) * i / (kSamples - 1);
      double e[kNumErrorTerms];
      layout.TermValues(all.data(), q, e);
      // An error function only counts relative to its axis' origin (the pose takes the constant); a squareness is
      // one angle and counts whole.
      const double v = squareness ? e[t] : e[t] - e0[t];
      if (std::abs(v) > std::abs(deviation)) deviation = v;
    }
    const double ratio = std::abs(deviation) / limit;
    if (!(ratio <= 1.0)) ++worst.beyond;
    if (!(ratio <= worst_ratio)) {
      worst_ratio = ratio;
      worst.share = ratio;
      worst.term = t;
      worst.deviation = deviation;
      worst.limit = limit;
      worst.coefficient.clear();
      worst.coefficient_value = 0;
      for (size_t c = 0; c < layout.coefficients().size(); ++c) {
        const ParameterLayout::Coefficient& coefficient = layout.coefficients()[c];
        if (coefficient.term == t && (worst.coefficient.empty() || std::abs(all[c]) > std::abs(worst.coefficient_value))) {
          worst.coefficient = coefficient.name;
          worst.coefficient_value = all[c];
        }
      }
      Eigen::Vector3d end = origin;
      end[axis] = travel.max;
      double e_end[kNumErrorTerms];
      layout.TermValues(all.data(), end, e_end);
      worst.slope = travel.max > travel.min ? (e_end[t] - e0[t]) / (travel.max - travel.min) : 0.0;
    }
  }
  return worst;
}

void CheckPlausibleMachine(const IdentificationResult& identified, double max_error_mm) {
  const ParameterLayout& layout = identified.calibration.layout;
  const bool is_default = !(max_error_mm > 0);
  const double bound = is_default ? DefaultMaxErrorMm(layout) : max_error_mm;
  if (std::isinf(bound)) return;
  const double longest = LongestTravel(layout);
  const TermExcess e = LargestExcess(identified.calibration, bound);
  if (e.term >= 0 && !(e.share <= 1.0)) {
    const ErrorTerm& term = GetErrorTerm(e.term);
    const bool translation = term.kind == ErrorKind::kTranslation;
    const int axis = static_cast<int>(layout.chain().ArgumentAxis(e.term));
    const Travel travel = layout.travel()[static_cast<size_t>(axis)];
    const auto value = [&](double v) { return translation ? Length(v) : Angle(v); };
    throw ImplausibleFit(fmt::format(
        "{} = {}: {} reaches {} over the {} travel of {:.4g} mm, beyond what any machine's error can be (bound {}{}){}; "
        "{}",
        e.coefficient, value(e.coefficient_value), term.vdi, value(e.deviation), static_cast<char>('X' + axis),
        travel.max - travel.min, BoundText(bound, longest, is_default),
        translation ? "" : fmt::format("; {} for angles", Angle(e.limit)),
        e.beyond > 1 ? fmt::format(", and {} more term(s) beyond it", e.beyond - 1) : std::string(), Diagnosis(term, e)));
  }
  // Residuals the model cannot bring below the bound: the readings are not this machine's at these commands.
  size_t worst = 0;
  for (size_t i = 1; i < identified.residuals.size(); ++i) {
    if (identified.residuals[i].norm() > identified.residuals[worst].norm()) worst = i;
  }
  if (!identified.residuals.empty() && !(identified.residuals[worst].norm() <= bound)) {
    throw ImplausibleFit(fmt::format(
        "reading {} stays {} from the identified machine (residual rms {}), beyond what any machine's error can be "
        "(bound {}): the readings cannot come from this machine at these commands; check that each reading belongs "
        "to its commanded point, the units (mm) and the tool offset",
        worst + 1, Length(identified.residuals[worst].norm()), Length(identified.residual_summary.rms_mm), BoundText(bound, longest, is_default)));
  }
}

void CheckReadingsSpan(const ParameterLayout& layout, const std::vector<Observation>& readings,
                       const std::vector<Eigen::Vector3d>& tool_offsets) {
  const Eigen::Index m = static_cast<Eigen::Index>(readings.size());
  if (m < 4) return;
  Eigen::Matrix3Xd measured(3, m), ideal(3, m);
  const double zero[kNumErrorTerms] = {};
  for (Eigen::Index i = 0; i < m; ++i) {
    const Observation& o = readings[static_cast<size_t>(i)];
    AxisChain chain = layout.chain();
    if (!tool_offsets.empty()) chain.tool_offset = tool_offsets.at(static_cast<size_t>(o.tool));
    measured.col(i) = o.measured;
    ideal.col(i) = ChainForward(chain, zero, o.command);
  }
  // Spread along the principal axes (singular values of the centred points, as rms): a rigid pose keeps them, a
  // machine's errors change them by parts per thousand at most.
  const auto spread = [&](const Eigen::Matrix3Xd& points) {
    const Eigen::Matrix3Xd centred = points.colwise() - points.rowwise().mean();
    return Eigen::Vector3d(Decompose<Eigen::JacobiSVD<Eigen::Matrix3Xd>>(centred, "the spread of the readings").singularValues() /
                           std::sqrt(static_cast<double>(m)));
  };
  const Eigen::Vector3d seen = spread(measured), commanded = spread(ideal);
  int collapsed = 0;
  for (int k = 0; k < 3; ++k) collapsed += seen[k] < 0.5 * commanded[k] ? 1 : 0;
  if (collapsed == 0) return;
  const char* shape = collapsed == 3 ? "every reading is (nearly) the same point"
                      : collapsed == 2 ? "the readings lie on a line"
                                       : "the readings lie in a plane";
  throw DegenerateReadings(fmt::format(
      "{}: they spread {:.4g}, {:.4g}, {:.4g} mm (rms along their principal axes) where the commanded points spread "
      "{:.4g}, {:.4g}, {:.4g} mm. A fit is rank-deficient here: only positioning errors as large as the travel (xTx1, "
      "yTy1, zTz1 near -100 %) could explain the readings, and at that solution the instrument's rotation (pose_rx, "
      "pose_ry, pose_rz) has no effect. Check that the reading columns hold the instrument's coordinates of each "
      "point (not a constant, repeated or copied column)",
      shape, seen[0], seen[1], seen[2], commanded[0], commanded[1], commanded[2]));
}

}  // namespace fvm::stage
