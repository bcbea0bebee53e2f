#include "artefacts/simulation/stitching_strategy.h"

#include <cmath>
#include <stdexcept>

#include "stage/inverse_model.h"

namespace fvm::artefacts {

void StrategyOptions::Check() const {
  if (!(fov_mm > 0) || !(overlap >= 0 && overlap < 1)) {
    throw std::invalid_argument("the field of view must be positive and the overlap in [0, 1)");
  }
}

StrategyRow PlanStrategyRow(const stage::ParameterLayout& layout, const std::vector<double>& values,
                            const Eigen::Vector3d& first, const Eigen::Vector3d& last, const StrategyOptions& options) {
  options.Check();
  const double length = (last - first).norm();
  if (!(length > 0)) throw std::invalid_argument("the two calottes must be apart");
  const double step = options.fov_mm * (1.0 - options.overlap);
  const int n = std::max(2, static_cast<int>(std::ceil(length / step)) + 1);
  StrategyRow row;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = first + (last - first) * (static_cast<double>(i) / (n - 1));
    const stage::InverseResult q = stage::Inverse(layout, values.data(), p);
    if (!q.converged) throw std::runtime_error("the stage model could not be inverted along the row");
    row.centres.push_back(p);
    row.commands.push_back(q.command);
  }
  return row;
}

std::vector<StrategyCase> StitchingStrategyCases(int n) {
  std::set<int> all_between, every_other;
  for (int i = 1; i < n - 1; ++i) {
    all_between.insert(i);
    if (i % 2 == 1) every_other.insert(i);
  }
  // With fewer than 4 tiles some cases miss nothing (n = 2) or coincide; a tile at either end is never missing.
  const auto inside = [n](int i) { return i > 0 && i < n - 1 ? std::set<int>{i} : std::set<int>{}; };
  return {
      {'a', "all tiles stitched", {}},
      {'b', "only the two end tiles", all_between},
      {'c', "the tile after the first missing", inside(1)},
      {'d', "a middle tile missing", inside(n / 2)},
      {'e', "the tile before the last missing", inside(n - 2)},
      {'f', "every other tile missing", every_other},
  };
}

std::vector<StrategyResult> SimulateStitchingStrategies(const StrategyRow& row) {
  const int n = static_cast<int>(row.centres.size());
  const Eigen::Vector3d& first = row.centres.front();
  const Eigen::Vector3d& last = row.centres.back();
  std::vector<StrategyResult> results;
  for (const StrategyCase& c : StitchingStrategyCases(n)) {
    StrategyResult r{c.id, c.description, n - static_cast<int>(c.missing.size()), {0}, 0.0, 0.0};
    // Walk the row: a tile whose predecessor is missing falls back to the encoders; the others inherit.
    int anchor = 0;
    for (int i = 1; i < n; ++i) {
      if (c.missing.contains(i)) continue;
      if (c.missing.contains(i - 1)) {
        anchor = i;
        r.encoder_tiles.push_back(i);
      }
    }
    // A tile placed by encoders at q reports its true point p as q: off by q - p, inherited along the chain.
    const Eigen::Vector3d measured_first = row.commands.front();
    const Eigen::Vector3d measured_last = last + (row.commands[static_cast<size_t>(anchor)] -
                                                  row.centres[static_cast<size_t>(anchor)]);
    r.distance_mm = (measured_last - measured_first).norm();
    r.distance_error_um = (r.distance_mm - (last - first).norm()) * 1e3;
    results.push_back(std::move(r));
  }
  return results;
}

std::vector<StrategyResult> SimulateStitchingStrategies(const stage::ParameterLayout& layout,
                                                        const std::vector<double>& values, const Eigen::Vector3d& first,
                                                        const Eigen::Vector3d& last, const StrategyOptions& options) {
  return SimulateStitchingStrategies(PlanStrategyRow(layout, values, first, last, options));
}

}  // namespace fvm::artefacts
