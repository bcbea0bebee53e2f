#include "stage/residual_findings.h"

#include "core/statistics.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace fvm::stage {
namespace {

double Correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const Eigen::Map<const Eigen::VectorXd> x(a.data(), static_cast<Eigen::Index>(a.size()));
  const Eigen::Map<const Eigen::VectorXd> y(b.data(), static_cast<Eigen::Index>(b.size()));
  const Eigen::VectorXd dx = x.array() - x.mean(), dy = y.array() - y.mean();
  const double d = dx.norm() * dy.norm();
  return d > 0 ? dx.dot(dy) / d : 0.0;
}

}  // namespace

std::vector<std::string> Findings(const std::vector<Eigen::Vector3d>& residuals, const MeasurementSet& set, double sigma) {
  std::vector<std::pair<double, std::string>> found;
  std::map<std::string, std::vector<double>> covariates;
  std::map<int, int> index_in_group;
  for (size_t i = 0; i < set.observations.size(); ++i) {
    const Observation& o = set.observations[i];
    covariates["x"].push_back(o.command.x());
    covariates["y"].push_back(o.command.y());
    covariates["height z"].push_back(o.command.z());
    covariates["calotte index"].push_back(index_in_group[o.group]++);
    if (!set.t_s.empty()) covariates["time"].push_back(set.t_s[i]);
  }
  for (int c = 0; c < 3; ++c) {
    std::vector<double> component;
    for (const Eigen::Vector3d& r : residuals) component.push_back(r[c]);
    for (const auto& [name, values] : covariates) {
      const double rho = Correlation(component, values);
      if (std::abs(rho) > 0.3) {
        found.emplace_back(std::abs(rho), fmt::format("residual {} follows {} (correlation {:+.2f})", "xyz"[c], name, rho));
      }
    }
  }
  std::map<int, std::pair<Eigen::Vector3d, int>> per_group;
  for (size_t i = 0; i < residuals.size(); ++i) {
    auto& [sum, n] = per_group[set.observations[i].group];
    if (n == 0) sum.setZero();
    sum += residuals[i];
    ++n;
  }
  for (const auto& [group, sum_n] : per_group) {
    const Eigen::Vector3d mean = sum_n.first / sum_n.second;
    const double z = mean.norm() / (sigma / std::sqrt(sum_n.second));
    if (z > 4) {
      const std::string name = static_cast<size_t>(group) < set.groups.size() ? set.groups[static_cast<size_t>(group)] : std::to_string(group);
      found.emplace_back(z / 10, fmt::format("placement {} sits {:.1f} um off on average ({:.1f} sigma)", name, mean.norm() * 1e3, z));
    }
  }
  size_t worst = 0;
  for (size_t i = 1; i < residuals.size(); ++i) {
    if (residuals[i].norm() > residuals[worst].norm()) worst = i;
  }
  if (!residuals.empty() && residuals[worst].norm() > 5 * sigma * std::sqrt(3.0)) {
    found.emplace_back(1.0, fmt::format("largest residual {:.1f} um at {} ({:.1f} sigma)", residuals[worst].norm() * 1e3,
                                        set.labels.empty() ? std::to_string(worst) : set.labels[worst],
                                        residuals[worst].norm() / sigma));
  }
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::string> out;
  for (size_t i = 0; i < found.size() && i < 5; ++i) out.push_back(found[i].second);
  if (out.empty()) out.push_back("no structure: residuals look like noise against position, height, time and index");
  return out;
}

double NeighbourNoise(const std::vector<Eigen::Vector3d>& residuals, const MeasurementSet& set) {
  std::map<int, std::vector<size_t>> placements;  // observations of each group, in measurement order
  for (size_t i = 0; i < set.observations.size() && i < residuals.size(); ++i) placements[set.observations[i].group].push_back(i);
  std::vector<double> second;
  for (const auto& [group, index] : placements) {
    for (size_t k = 1; k + 1 < index.size(); ++k) {
      const Eigen::Vector3d d = residuals[index[k + 1]] - 2.0 * residuals[index[k]] + residuals[index[k - 1]];
      second.insert(second.end(), {std::abs(d.x()), std::abs(d.y()), std::abs(d.z())});
    }
  }
  if (second.empty()) return 0.0;
  return 1.4826 * Median(std::move(second)) / std::sqrt(6.0);
}

}  // namespace fvm::stage
