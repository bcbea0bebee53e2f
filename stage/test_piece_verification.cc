#include "stage/test_piece_verification.h"

#include <string_view>

#include "stage/calibration.h"
#include "stage/error_terms.h"

namespace fvm::stage {

std::vector<TermRecovery> TermRecoveries(const IdentificationResult& identified) {
  const Calibration& cal = identified.calibration;
  Eigen::Vector3d origin, far_end;
  for (int k = 0; k < 3; ++k) {
    origin[k] = cal.layout.travel()[static_cast<size_t>(k)].min;
    far_end[k] = cal.layout.travel()[static_cast<size_t>(k)].max;
  }
  // Each term at the far end of its own axis (squareness: anywhere), the other axes at their origin.
  std::vector<TermRecovery> out;
  for (int t = 0; t < kNumErrorTerms; ++t) {
    const ErrorTerm& term = GetErrorTerm(t);
    TermRecovery r;
    r.error = std::string(term.iso);
    r.vdi = std::string(term.vdi);
    Eigen::Vector3d q = origin;
    const int axis = static_cast<int>(cal.layout.chain().ArgumentAxis(t));
    q[axis] = far_end[axis];
    const TermValuesWithUncertainty v = TermValuesAt(cal, q, term.kind == ErrorKind::kSquareness ? nullptr : &origin);
    const double unit = term.kind == ErrorKind::kTranslation ? 1e3 : 1e6;
    r.value = v.value[t] * unit;
    r.u = v.u[t] * unit;
    int present = 0, fixed = 0;
    for (const ParameterLayout::Coefficient& c : cal.layout.coefficients()) {
      if (c.term != t) continue;
      ++present;
      for (const FixedCoefficient& f : identified.fixed) {
        if (f.name != c.name) continue;
        ++fixed;
        if (r.reason.empty()) r.reason = f.name + ": " + f.reason;
      }
    }
    // The constant of a translation or rotation term is no part of the error function (it vanishes at the origin,
    // where the datum takes it), so only the other coefficients decide.
    int constants_fixed = 0;
    for (const ParameterLayout::Coefficient& c : cal.layout.coefficients()) {
      if (c.term != t || c.power != 0 || term.kind == ErrorKind::kSquareness) continue;
      for (const FixedCoefficient& f : identified.fixed) constants_fixed += f.name == c.name ? 1 : 0;
      --present;
    }
    fixed -= constants_fixed;
    if (constants_fixed > 0 && fixed == 0) r.reason.clear();
    r.recoverable = present > 0 && fixed == 0;
    r.partly = fixed > 0 && fixed < present;
    out.push_back(r);
  }
  return out;
}

TestPieceVerification VerifyTestPiece(const ParameterLayout& layout, const std::vector<Observation>& readings,
                                      IdentificationOptions options) {
  std::vector<VolumetricError> log;
  options.on_iteration = [&](const ParameterLayout& solved, const std::vector<double>& values, const Pose& pose) {
    log.push_back(SummarizeVolumetric(VolumetricResiduals(solved, &values, pose, readings, options.tool_offsets)));
  };
  TestPieceVerification out(VerifyMachine(layout, readings, options));
  out.iterations.push_back(out.result.initial);
  out.iterations.insert(out.iterations.end(), log.begin(), log.end());
  out.terms = TermRecoveries(out.result.identified);
  for (const FixedCoefficient& f : out.result.identified.fixed) {
    if (f.reason.find("instrument pose absorbs") != std::string::npos) out.datum_absorbs.push_back(f);
  }
  return out;
}

}  // namespace fvm::stage
