#include "stage/fvm_stage_models.h"

#include <cctype>
#include <sstream>
#include <stdexcept>

namespace fvm::stage {

std::array<Travel, 3> FvmStageTravel() { return {Travel{-200.0, 0.0}, Travel{-200.0, 0.0}, Travel{-100.0, 0.0}}; }

std::vector<std::string> FvmModelNames() { return {"9", "15", "27", "42"}; }

ParameterLayout FvmModelLayout(std::string_view model, const std::array<Travel, 3>& travel, Basis basis) {
  ParameterLayout layout(AxisChain::FvmStage(), travel);
  if (model == "9") {
    layout.SetTerm("xTx", basis, 1);
    layout.SetTerm("xTy", basis, 0);
    layout.SetTerm("xTz", basis, 0);
    layout.SetTerm("yTy", basis, 1);
    layout.Drop("yTy0");  // combined with xTy0 ([Pérez 2019] eq. 15)
    layout.SetTerm("yRz", basis, 0);
    for (const char* w : {"xWy", "xWz", "yWz"}) layout.SetTerm(w, basis, 0);
    return layout;
  }
  int order = -1;
  if (model == "15") order = 0;
  if (model == "27") order = 1;
  if (model == "42") order = 2;
  if (order < 0) {
    throw std::invalid_argument("unknown model '" + std::string(model) + "': use 9, 15, 27 or 42, or --terms");
  }
  for (const char* axis : {"x", "y"}) {
    for (const char* kind : {"Tx", "Ty", "Tz", "Rx", "Ry", "Rz"}) layout.SetTerm(std::string(axis) + kind, basis, order);
  }
  for (const char* w : {"xWy", "xWz", "yWz"}) layout.SetTerm(w, basis, order);
  if (order >= 1) {
    for (const char* c : {"xTy1", "xTz1", "yTz1"}) layout.Drop(c);
  }
  return layout;
}

ParameterLayout ComposeLayout(std::string_view terms, const AxisChain& chain, const std::array<Travel, 3>& travel) {
  ParameterLayout layout(chain, travel);
  std::stringstream items{std::string(terms)};
  std::string item;
  while (std::getline(items, item, ',')) {
    if (item.empty()) continue;
    std::vector<std::string> parts;
    std::stringstream fields(item);
    for (std::string f; std::getline(fields, f, ':');) parts.push_back(f);
    Basis basis = Basis::kPower;
    int order = 0;
    for (size_t i = 1; i < parts.size(); ++i) {
      if (const auto b = ParseBasis(parts[i])) {
        basis = *b;
      } else if (parts[i].size() == 1 && std::isdigit(static_cast<unsigned char>(parts[i][0]))) {
        order = parts[i][0] - '0';
      } else {
        throw std::invalid_argument("--terms item '" + item + "': '" + parts[i] +
                                    "' is neither a basis (power, legendre, chebyshev) nor an order 0..3");
      }
    }
    try {
      layout.SetTerm(parts[0], basis, order);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("--terms item '" + item + "': " + e.what());
    }
  }
  if (layout.NumFree() == 0) throw std::invalid_argument("--terms names no error term");
  return layout;
}

}  // namespace fvm::stage
