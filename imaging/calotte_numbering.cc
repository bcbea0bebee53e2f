#include "imaging/calotte_numbering.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/input_error.h"
#include "imaging/calotte_detection.h"

namespace fvm::imaging {
namespace {

using Complex = std::complex<double>;

Complex AsComplex(const Eigen::Vector2d& v) { return {v.x(), v.y()}; }

// map = a nominal + b with a = scale e^{i rotation}: a similarity in the plane is a complex affine map.
struct Similarity {
  Complex a{1.0, 0.0};
  Complex b{0.0, 0.0};
  Complex operator()(const Complex& z) const { return a * z + b; }
};

double NearestDistance(const std::vector<Eigen::Vector2d>& points, std::size_t i) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < points.size(); ++j) {
    if (j != i) best = std::min(best, (points[j] - points[i]).norm());
  }
  return best;
}

// Ordered pairs (i, j) with j among i's nearest neighbours (within 5 % of the nearest distance): the edges a
// hypothesis is anchored on. A grid gives its 4-neighbours, a bar its two neighbours.
std::vector<std::pair<std::size_t, std::size_t>> NeighbourPairs(const std::vector<Eigen::Vector2d>& points) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double nearest = NearestDistance(points, i);
    for (std::size_t j = 0; j < points.size(); ++j) {
      if (j != i && (points[j] - points[i]).norm() <= 1.05 * nearest) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

// Each found calotte's nominal index under the transform (-1 when none is within the tolerance).
std::vector<int> Assign(const std::vector<Complex>& found, const std::vector<Complex>& nominal, const Similarity& t,
                        double tolerance, int* matched) {
  std::vector<Complex> placed(nominal.size());
  for (std::size_t j = 0; j < nominal.size(); ++j) placed[j] = t(nominal[j]);
  std::vector<int> assignment(found.size(), -1);
  *matched = 0;
  for (std::size_t i = 0; i < found.size(); ++i) {
    double best = tolerance * tolerance;  // squared distances: no square root in the inner loop
    for (std::size_t j = 0; j < placed.size(); ++j) {
      const double d2 = std::norm(found[i] - placed[j]);
      if (d2 <= best) best = d2, assignment[i] = static_cast<int>(j);
    }
    *matched += assignment[i] >= 0;
  }
  return assignment;
}

double WrapAngle(double a) { return std::remainder(a, 2 * M_PI); }

std::string Degrees(double rad) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1f", rad * 180 / M_PI);
  return buffer;
}

}  // namespace

void LayoutMatchOptions::Check() const {
  if (!std::isfinite(expected_rotation_rad)) throw std::invalid_argument("layout match: rotation must be finite");
  if (!(tolerance_mm >= 0) || !(max_scale_error > 0 && max_scale_error < 1) || !(ambiguity_margin_rad >= 0)) {
    throw std::invalid_argument("layout match: tolerance, scale error and ambiguity margin must be positive");
  }
}

LayoutMatch MatchLayout(const std::vector<Eigen::Vector2d>& found, const std::vector<NominalCalotte>& nominal,
                        const LayoutMatchOptions& options) {
  options.Check();
  if (nominal.empty()) throw std::invalid_argument("layout match: the nominal layout is empty");
  if (found.empty()) throw InputError("no calotte was found, so none can be numbered");
  LayoutMatch out;
  if (nominal.size() == 1) {
    // One nominal calotte has no pattern to match: the one found is it.
    if (found.size() != 1) {
      throw InputError("the layout has one calotte but " + std::to_string(found.size()) + " were found");
    }
    out.ids = {nominal[0].id};
    out.matched = 1;
    out.translation_mm = found[0] - nominal[0].xy_mm;
    return out;
  }
  if (found.size() < 2) {
    throw InputError("one calotte was found; which of the layout's " + std::to_string(nominal.size()) +
                     " it is cannot be told from one position. Measure it with a neighbour");
  }

  std::vector<Eigen::Vector2d> nominal_xy;
  for (const auto& c : nominal) nominal_xy.push_back(c.xy_mm);
  double spacing = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < nominal_xy.size(); ++i) spacing = std::min(spacing, NearestDistance(nominal_xy, i));
  if (!(spacing > 0)) throw std::invalid_argument("layout match: two nominal calottes coincide");
  const double tolerance = options.tolerance_mm > 0 ? options.tolerance_mm : 0.25 * spacing;

  std::vector<Complex> f, n;
  for (const auto& p : found) f.push_back(AsComplex(p));
  for (const auto& p : nominal_xy) n.push_back(AsComplex(p));

  struct Candidate {
    std::vector<int> assignment;
    double rotation;
  };
  std::vector<Candidate> best;
  int best_count = 0;
  const auto found_pairs = NeighbourPairs(found);
  const auto nominal_pairs = NeighbourPairs(nominal_xy);
  for (const auto& [i, k] : found_pairs) {
    const Complex vf = f[k] - f[i];
    for (const auto& [a, b] : nominal_pairs) {
      const Complex vn = n[b] - n[a];
      const Complex ratio = vf / vn;
      if (std::abs(std::abs(ratio) - 1.0) > options.max_scale_error) continue;
      const Similarity t{ratio, f[i] - ratio * n[a]};
      int count = 0;
      std::vector<int> assignment = Assign(f, n, t, tolerance, &count);
      if (count < best_count) continue;
      if (count > best_count) best.clear(), best_count = count;
      const bool known =
          std::any_of(best.begin(), best.end(), [&](const Candidate& c) { return c.assignment == assignment; });
      if (!known) best.push_back({std::move(assignment), std::arg(ratio)});
    }
  }
  if (best_count < 2) {
    throw InputError("the " + std::to_string(found.size()) +
                     " calottes found do not match the nominal layout (no two of them at a nominal spacing of the "
                     "artefact within " +
                     std::to_string(100 * options.max_scale_error) +
                     " %); is it the right artefact, and is the map in mm?");
  }
  std::sort(best.begin(), best.end(), [&](const Candidate& p, const Candidate& q) {
    return std::abs(WrapAngle(p.rotation - options.expected_rotation_rad)) <
           std::abs(WrapAngle(q.rotation - options.expected_rotation_rad));
  });
  if (best.size() > 1) {
    const double d0 = std::abs(WrapAngle(best[0].rotation - options.expected_rotation_rad));
    const double d1 = std::abs(WrapAngle(best[1].rotation - options.expected_rotation_rad));
    if (d1 - d0 < options.ambiguity_margin_rad) {
      const bool same_turn = std::abs(WrapAngle(best[0].rotation - best[1].rotation)) < options.ambiguity_margin_rad;
      throw InputError(
          same_turn ? "the " + std::to_string(found.size()) +
                          " calottes found fit the nominal layout in more than one "
                          "place (a partial view of a regular pattern): their numbers cannot be told. Measure a view "
                          "that shows the artefact's corners or ends"
                    : "the calottes found fit the nominal layout turned by " + Degrees(best[0].rotation) + " and by " +
                          Degrees(best[1].rotation) + " degrees, equally far from the expected " +
                          Degrees(options.expected_rotation_rad) + "; say how the artefact lies (e.g. --rotation-deg " +
                          Degrees(best[0].rotation) + ")");
    }
  }

  // Least squares similarity over the matched pairs: a = sum (w - w_mean) conj(z - z_mean) / sum |z - z_mean|^2.
  const auto refine = [&](const std::vector<int>& assignment) {
    Complex zm = 0, wm = 0;
    int m = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (assignment[i] < 0) continue;
      zm += n[static_cast<std::size_t>(assignment[i])], wm += f[i], ++m;
    }
    zm /= static_cast<double>(m), wm /= static_cast<double>(m);
    Complex num = 0;
    double den = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (assignment[i] < 0) continue;
      const Complex z = n[static_cast<std::size_t>(assignment[i])] - zm;
      num += (f[i] - wm) * std::conj(z), den += std::norm(z);
    }
    const Complex a = num / den;
    return Similarity{a, wm - a * zm};
  };
  Similarity t = refine(best[0].assignment);
  std::vector<int> assignment = Assign(f, n, t, tolerance, &out.matched);
  t = refine(assignment);

  double sum2 = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (assignment[i] < 0) {
      out.ids.push_back(0);
      continue;
    }
    out.ids.push_back(nominal[static_cast<std::size_t>(assignment[i])].id);
    sum2 += std::norm(f[i] - t(n[static_cast<std::size_t>(assignment[i])]));
  }
  out.rotation_rad = std::arg(t.a);
  out.scale = std::abs(t.a);
  out.translation_mm = Eigen::Vector2d(t.b.real(), t.b.imag());
  out.rms_mm = std::sqrt(sum2 / out.matched);
  return out;
}

void NumberCalottes(CalotteDetection& detection, const std::vector<NominalCalotte>& nominal,
                    const LayoutMatchOptions& options) {
  std::vector<Eigen::Vector2d> found;
  for (const auto& c : detection.calottes) found.push_back(c.fit.centre_mm.head<2>());
  const LayoutMatch match = MatchLayout(found, nominal, options);
  std::vector<DetectedCalotte> numbered;
  for (std::size_t i = 0; i < detection.calottes.size(); ++i) {
    DetectedCalotte& c = detection.calottes[i];
    if (match.ids[i] > 0) {
      c.id = match.ids[i];
      numbered.push_back(std::move(c));
      continue;
    }
    RejectedRegion region;
    region.centre_mm = c.fit.centre_mm.head<2>();
    region.extent_mm = c.extent_mm;
    region.points = c.fit.points;
    region.reason = "a spherical dimple, but at no calotte of the nominal layout";
    detection.rejected.push_back(region);
  }
  std::sort(numbered.begin(), numbered.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  detection.calottes = std::move(numbered);
}

}  // namespace fvm::imaging
