#include "artefacts/stitching_strategy.h"

#include <cmath>
#include <set>
#include <stdexcept>

#include "stage/inverse_model.h"

namespace fvm::artefacts {

void StrategyOptions::Check() const {
  if (!(fov_mm > 0) || !(overlap >= 0 && overlap < 1)) {
    throw std::invalid_argument("the field of view must be positive and the overlap in [0, 1)");
  }
}

std::vector<StrategyResult> SimulateStitchingStrategies(const stage::ParameterLayout& layout,
                                                        const std::vector<double>& values, const Eigen::Vector3d& first,
                                                        const Eigen::Vector3d& last, const StrategyOptions& options) {
  options.Check();
  const double length = (last - first).norm();
  if (!(length > 0)) throw std::invalid_argument("the two calottes must be apart");
  // Tile centres along the row, the first on the first calotte, the last on the last one.
  const double step = options.fov_mm * (1.0 - options.overlap);
  const int n = std::max(2, static_cast<int>(std::ceil(length / step)) + 1);
  std::vector<Eigen::Vector3d> centres;  // true positions under the tile centres
  for (int i = 0; i < n; ++i) centres.push_back(first + (last - first) * (static_cast<double>(i) / (n - 1)));
  // Where the stage must be commanded for each tile, and the error it reports there.
  std::vector<Eigen::Vector3d> report_offset;  // reported - true, for a tile placed by encoders
  for (const Eigen::Vector3d& p : centres) {
    const stage::InverseResult q = stage::Inverse(layout, values.data(), p);
    if (!q.converged) throw std::runtime_error("the stage model could not be inverted along the row");
    report_offset.push_back(q.command - p);
  }

  struct Case {
    char id;
    const char* description;
    std::set<int> missing;
  };
  std::set<int> all_between, every_other;
  for (int i = 1; i < n - 1; ++i) {
    all_between.insert(i);
    if (i % 2 == 1) every_other.insert(i);
  }
  const std::vector<Case> cases = {
      {'a', "all tiles stitched", {}},
      {'b', "only the two end tiles", all_between},
      {'c', "the tile after the first missing", {1}},
      {'d', "a middle tile missing", {n / 2}},
      {'e', "the tile before the last missing", {n - 2}},
      {'f', "every other tile missing", every_other},
  };
  std::vector<StrategyResult> results;
  for (const Case& c : cases) {
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
    const Eigen::Vector3d measured_first = first + report_offset[0];
    const Eigen::Vector3d measured_last = last + report_offset[static_cast<size_t>(anchor)];
    r.distance_mm = (measured_last - measured_first).norm();
    r.distance_error_um = (r.distance_mm - length) * 1e3;
    results.push_back(std::move(r));
  }
  return results;
}

}  // namespace fvm::artefacts
