#pragma once
// Polynomial bases for error functions of a linear axis, on a coordinate normalised to the axis travel.

#include <optional>
#include <stdexcept>
#include <string_view>

namespace fvm::stage {

enum class Basis { kPower, kLegendre, kChebyshev };

std::string_view BasisName(Basis basis);
std::optional<Basis> ParseBasis(std::string_view name);

// Travel of one axis in mm. The normalised coordinate u is q / half-travel for the power basis (so a power
// coefficient keeps its published meaning up to a scale factor and xTy1 stays an exact alias of xWy), and
// (q - mid-travel) / half-travel in [-1, 1] for Legendre and Chebyshev (where orthogonality needs it).
struct Travel {
  double min = -100.0;
  double max = 100.0;
  double Mid() const { return 0.5 * (min + max); }
  double Half() const { return 0.5 * (max - min); }
  void Check() const {
    if (!(max > min)) throw std::invalid_argument("axis travel must have max > min");
  }
};

template <typename T>
T NormalisedCoordinate(Basis basis, const Travel& travel, const T& q) {
  if (basis == Basis::kPower) return q / travel.Half();
  return (q - travel.Mid()) / travel.Half();
}

// Writes the order + 1 basis functions at u into out[0..order].
template <typename T>
void EvaluateBasis(Basis basis, int order, const T& u, T* out) {
  out[0] = T(1.0);
  if (order >= 1) out[1] = u;
  for (int n = 1; n < order; ++n) {
    switch (basis) {
      case Basis::kPower:
        out[n + 1] = out[n] * u;
        break;
      case Basis::kLegendre:  // (n + 1) P_{n+1} = (2n + 1) u P_n - n P_{n-1}
        out[n + 1] = (double(2 * n + 1) * u * out[n] - double(n) * out[n - 1]) / double(n + 1);
        break;
      case Basis::kChebyshev:  // T_{n+1} = 2 u T_n - T_{n-1}
        out[n + 1] = 2.0 * u * out[n] - out[n - 1];
        break;
    }
  }
}

}  // namespace fvm::stage
