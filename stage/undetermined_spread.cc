#include "stage/undetermined_spread.h"

#include <cmath>
#include <map>
#include <utility>

#include "stage/error_terms.h"

namespace fvm::stage {

Eigen::VectorXd UndeterminedPrior(const Calibration& calibration) {
  const ParameterLayout& layout = calibration.layout;
  const auto kin_of = [&](const ParameterLayout::Coefficient& c) {
    return std::make_pair(static_cast<int>(GetErrorTerm(c.term).kind), c.power);
  };
  std::map<std::pair<int, int>, std::pair<double, int>> kin;  // (kind, power) -> (sum of squares, count)
  for (const ParameterLayout::Coefficient& c : layout.coefficients()) {
    const int slot = layout.FreeIndexOf(c.name);
    if (slot < 0) continue;
    std::pair<double, int>& k = kin[kin_of(c)];
    k.first += std::pow(calibration.values[static_cast<size_t>(slot)], 2);
    ++k.second;
  }
  const std::vector<std::string>& names = calibration.undetermined.names;
  Eigen::VectorXd prior = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(names.size()));
  for (size_t i = 0; i < names.size(); ++i) {
    const int index = layout.FindCoefficient(names[i]);
    if (index < 0) continue;
    const auto it = kin.find(kin_of(layout.coefficients()[static_cast<size_t>(index)]));
    if (it != kin.end()) prior[static_cast<Eigen::Index>(i)] = it->second.first / it->second.second;
  }
  return prior;
}

std::optional<Calibration> UndeterminedSpread(const Calibration& calibration) {
  const Calibration::Undetermined& u = calibration.undetermined;
  const Eigen::Index n = static_cast<Eigen::Index>(calibration.values.size());
  if (u.names.empty() || u.absorbed.rows() != n || u.absorbed.cols() != static_cast<Eigen::Index>(u.names.size())) {
    return std::nullopt;
  }
  Calibration freed = calibration;
  freed.undetermined = {};
  for (const std::string& name : u.names) {
    if (calibration.layout.FindCoefficient(name) < 0 || calibration.layout.FreeIndexOf(name) >= 0) return std::nullopt;
    freed.layout.Free(name);
  }
  const Eigen::Index all = freed.layout.NumFree();
  freed.values.assign(static_cast<size_t>(all), 0.0);
  Eigen::MatrixXd e = Eigen::MatrixXd::Zero(all, u.absorbed.cols());  // d(error of each free coefficient) / d(true value)
  const std::vector<std::string> free_names = calibration.layout.FreeNames();
  for (Eigen::Index i = 0; i < n; ++i) {
    const int slot = freed.layout.FreeIndexOf(free_names[static_cast<size_t>(i)]);
    freed.values[static_cast<size_t>(slot)] = calibration.values[static_cast<size_t>(i)];
    e.row(slot) = u.absorbed.row(i);
  }
  for (size_t k = 0; k < u.names.size(); ++k) {
    const int slot = freed.layout.FreeIndexOf(u.names[k]);
    freed.values[static_cast<size_t>(slot)] = calibration.layout.coefficients()[static_cast<size_t>(calibration.layout.FindCoefficient(u.names[k]))].value;
    e(slot, static_cast<Eigen::Index>(k)) = -1.0;
  }
  freed.covariance = e * UndeterminedPrior(calibration).asDiagonal() * e.transpose();
  return freed;
}

}  // namespace fvm::stage
