#include "stage/machined_piece_verification.h"

#include <cmath>
#include <string_view>

#include "stage/calibration.h"
#include "stage/error_terms.h"

namespace fvm::stage {

std::vector<TermRecovery> TermRecoveries(const IdentificationResult& identified) {
  const Calibration& cal = identified.calibration;
  Eigen::Vector3d origin;
  for (int k = 0; k < 3; ++k) origin[k] = cal.layout.travel()[static_cast<size_t>(k)].min;
  std::vector<TermRecovery> out;
  for (int t = 0; t < kNumErrorTerms; ++t) {
    const ErrorTerm& term = GetErrorTerm(t);
    TermRecovery r;
    r.error = std::string(term.iso);
    r.vdi = std::string(term.vdi);
    // Which coefficients the rank treatment fixed. A constant is no part of an error function (it vanishes at the
    // axis' origin, where the datum takes it); a fixed linear coefficient of a straightness or a rotation is the
    // datum's turn or a squareness, so the term is recovered only up to its chord ("partly").
    int present = 0, fixed = 0, linear_fixed = 0;
    for (const ParameterLayout::Coefficient& c : cal.layout.coefficients()) {
      if (c.term != t || (c.power == 0 && term.kind != ErrorKind::kSquareness)) continue;
      ++present;
      for (const FixedCoefficient& f : identified.fixed) {
        if (f.name != c.name) continue;
        ++fixed;
        linear_fixed += c.power == 1 ? 1 : 0;
        if (r.reason.empty()) r.reason = f.name + ": " + f.reason;
      }
    }
    r.recoverable = present > 0 && fixed == 0;
    r.partly = fixed > 0 && fixed < present;
    // The value: the largest deviation over the axis' travel from the origin (from the chord when the linear part
    // went to the datum), signed, with its standard uncertainty.
    const int axis = static_cast<int>(cal.layout.chain().ArgumentAxis(t));
    const Travel travel = cal.layout.travel()[static_cast<size_t>(axis)];
    const double unit = term.kind == ErrorKind::kTranslation ? 1e3 : 1e6;
    constexpr int kSamples = 61;
    Eigen::Vector3d end = origin;
    end[axis] = travel.max;
    const TermValuesWithUncertainty at_end = TermValuesAt(cal, end, &origin);
    for (int i = 0; i < kSamples; ++i) {
      Eigen::Vector3d q = origin;
      const double share = static_cast<double>(i) / (kSamples - 1);
      q[axis] = travel.min + share * (travel.max - travel.min);
      const TermValuesWithUncertainty v = TermValuesAt(cal, q, term.kind == ErrorKind::kSquareness ? nullptr : &origin);
      const double value = (v.value[t] - (linear_fixed > 0 ? share * at_end.value[t] : 0.0)) * unit;
      if (std::abs(value) >= std::abs(r.value)) {
        r.value = value;
        r.u = v.u[t] * unit;
      }
    }
    out.push_back(r);
  }
  return out;
}

MachinedPieceVerification VerifyMachinedPiece(const ParameterLayout& layout, const std::vector<Observation>& readings,
                                      IdentificationOptions options) {
  std::vector<ResidualSummary> log;
  options.on_iteration = [&](const ParameterLayout& solved, const std::vector<double>& values, const Pose& pose) {
    log.push_back(Summarize(VolumetricResiduals(solved, &values, pose, readings, options.tool_offsets)));
  };
  MachinedPieceVerification out(VerifyMachine(layout, readings, options));
  out.iterations.push_back(out.result.initial);
  out.iterations.insert(out.iterations.end(), log.begin(), log.end());
  out.terms = TermRecoveries(out.result.identified);
  for (const FixedCoefficient& f : out.result.identified.fixed) {
    if (f.reason.find("instrument pose absorbs") != std::string::npos) out.datum_absorbs.push_back(f);
  }
  return out;
}

}  // namespace fvm::stage
