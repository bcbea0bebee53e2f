#include "stage/polynomial_basis.h"

namespace fvm::stage {

std::string_view BasisName(Basis basis) {
  switch (basis) {
    case Basis::kPower: return "power";
    case Basis::kLegendre: return "legendre";
    case Basis::kChebyshev: return "chebyshev";
  }
  return "?";
}

std::optional<Basis> ParseBasis(std::string_view name) {
  for (Basis b : {Basis::kPower, Basis::kLegendre, Basis::kChebyshev}) {
    if (BasisName(b) == name) return b;
  }
  return std::nullopt;
}

}  // namespace fvm::stage
