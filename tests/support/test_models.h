#pragma once
// Error sets shared by the stage tests: realistic magnitudes from the published FVM work ([Pérez 2019]; translations of
// 100-200 um over the travel, rotations of 1e-4 rad), drawn with a fixed seed.

#include <random>

#include "stage/parameter_layout.h"

namespace fvm::stage::testing {

inline std::array<Travel, 3> FvmTravel() { return {Travel{-200.0, 0.0}, Travel{-200.0, 0.0}, Travel{-100.0, 0.0}}; }

// Every T and R term of the axes that `axes` names, as polynomials of `order`, and the three squareness terms.
inline ParameterLayout FullLayout(const AxisChain& chain, const std::array<Travel, 3>& travel, int order,
                                  const std::string& axes = "xy", Basis basis = Basis::kPower) {
  ParameterLayout layout(chain, travel);
  for (char a : axes) {
    for (const char* kind : {"Tx", "Ty", "Tz", "Rx", "Ry", "Rz"}) layout.SetTerm(std::string(1, a) + kind, basis, order);
  }
  for (const char* w : {"xWy", "xWz", "yWz"}) layout.SetTerm(w, basis, 0);
  return layout;
}

// Random coefficients: translations up to `t_mm`, rotations and squareness up to `r_rad`, uniformly signed.
inline std::vector<double> RandomCoefficients(const ParameterLayout& layout, unsigned seed, double t_mm = 0.15,
                                              double r_rad = 2e-4) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<double> values;
  for (const auto& c : layout.coefficients()) {
    if (c.state != ParameterLayout::State::kFree) continue;
    const ErrorKind kind = GetErrorTerm(c.term).kind;
    values.push_back(unit(rng) * (kind == ErrorKind::kTranslation ? t_mm : r_rad));
  }
  return values;
}

}  // namespace fvm::stage::testing
