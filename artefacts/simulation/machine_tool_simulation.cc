#include "artefacts/simulation/machine_tool_simulation.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/number_text.h"
#include "core/random.h"

namespace fvm::artefacts {
namespace {

constexpr double kPi = std::numbers::pi;

using fvm::Random;  // core/random.h: the same bits with any standard library

double RoundToMicrometre(double mm) { return std::round(mm * 1000.0) / 1000.0; }

// Mesh nodes of one axis: min, min + step, ..., and max (a shorter last step when the travel is no multiple).
std::vector<double> Nodes(double min, double max, double step, char axis) {
  if (!(step > 0.0) || !std::isfinite(step)) {
    throw std::invalid_argument(fmt::format("mesh step of {} must be a positive number of mm, not {}", axis, step));
  }
  const double travel = max - min;
  const double intervals = std::floor(travel / step + 1e-9);
  if (intervals > 100'000.0) {
    throw std::invalid_argument(fmt::format("mesh step of {} ({} mm) makes more than 100000 points along the {} mm "
                                            "travel",
                                            axis, step, travel));
  }
  std::vector<double> nodes;
  for (int i = 0; i <= static_cast<int>(intervals); ++i) nodes.push_back(RoundToMicrometre(min + i * step));
  if (max - nodes.back() > 1e-6) nodes.push_back(RoundToMicrometre(max));
  nodes.back() = max;
  return nodes;
}

std::string PointId(size_t index) { return fmt::format("P{:04d}", index + 1); }

// Approach of each point: the sign of the last non-zero X motion before it; the first point counts as +x.
void SetApproach(std::vector<PlannedPoint>& points) {
  bool positive = true;
  for (size_t i = 0; i < points.size(); ++i) {
    if (i > 0) {
      const double dx = points[i].nominal.x() - points[i - 1].nominal.x();
      if (dx > 0.0) positive = true;
      if (dx < 0.0) positive = false;
    }
    points[i].approach = positive ? "+x" : "-x";
  }
}

// Node indices of the serpentine mesh in visiting order.
std::vector<std::array<size_t, 3>> SerpentineOrder(const std::array<size_t, 3>& counts) {
  std::vector<std::array<size_t, 3>> order;
  order.reserve(counts[0] * counts[1] * counts[2]);
  size_t row = 0;
  for (size_t k = 0; k < counts[2]; ++k) {
    for (size_t jj = 0; jj < counts[1]; ++jj) {
      const size_t j = k % 2 == 0 ? jj : counts[1] - 1 - jj;
      for (size_t ii = 0; ii < counts[0]; ++ii) {
        const size_t i = row % 2 == 0 ? ii : counts[0] - 1 - ii;
        order.push_back({i, j, k});
      }
      ++row;
    }
  }
  return order;
}

constexpr size_t kMaxPlannedPoints = 10'000'000;

std::array<std::vector<double>, 3> MeshNodes(const Workspace& ws, const Eigen::Vector3d& step) {
  ws.Check();
  std::array<std::vector<double>, 3> nodes;
  double total = 1.0;
  for (int k = 0; k < 3; ++k) {
    nodes[static_cast<size_t>(k)] = Nodes(ws.min[k], ws.max[k], step[k], "xyz"[k]);
    total *= static_cast<double>(nodes[static_cast<size_t>(k)].size());
  }
  if (total > static_cast<double>(kMaxPlannedPoints)) {
    throw std::invalid_argument(fmt::format("the mesh would have {:.0f} points; more than {} is no verification "
                                            "plan: take larger steps",
                                            total, kMaxPlannedPoints));
  }
  return nodes;
}

}  // namespace

std::vector<PlannedPoint> PlanMesh(const Workspace& ws, const Eigen::Vector3d& step) {
  const auto nodes = MeshNodes(ws, step);
  std::vector<PlannedPoint> points;
  for (const auto& index : SerpentineOrder({nodes[0].size(), nodes[1].size(), nodes[2].size()})) {
    PlannedPoint p;
    p.id = PointId(points.size());
    p.nominal = {nodes[0][index[0]], nodes[1][index[1]], nodes[2][index[2]]};
    points.push_back(std::move(p));
  }
  SetApproach(points);
  return points;
}

std::vector<PlannedPoint> PlanCloud(const Workspace& ws, const Eigen::Vector3d& step, std::uint64_t seed) {
  const auto nodes = MeshNodes(ws, step);
  Random random(seed);
  std::vector<PlannedPoint> points;
  for (const auto& index : SerpentineOrder({nodes[0].size(), nodes[1].size(), nodes[2].size()})) {
    PlannedPoint p;
    p.id = PointId(points.size());
    for (int k = 0; k < 3; ++k) {
      const std::vector<double>& axis = nodes[static_cast<size_t>(k)];
      const size_t i = index[static_cast<size_t>(k)];
      const double u = random.Uniform();  // drawn for every coordinate, so the sequence does not depend on the mesh
      double v = axis[i];
      if (i > 0 && i + 1 < axis.size()) {
        // Within half the gap to each neighbour: the point stays in its node's cell (and inside the travel when the
        // last step is shorter).
        const double below = 0.5 * (axis[i] - axis[i - 1]);
        const double above = 0.5 * (axis[i + 1] - axis[i]);
        v = RoundToMicrometre(axis[i] - below + u * (below + above));
      }
      p.nominal[k] = v;
    }
    points.push_back(std::move(p));
  }
  SetApproach(points);
  return points;
}

std::vector<PlannedPoint> PlanDiagonals(const Workspace& ws, int points_per_diagonal) {
  ws.Check();
  if (points_per_diagonal < 2 || points_per_diagonal > 1'000'000) {
    throw std::invalid_argument(
        fmt::format("points per diagonal must be 2 .. 1000000 (both corners count), not {}", points_per_diagonal));
  }
  // Start corners as (x, y) at the min (0) or max (1) end; each diagonal runs from z min to z max to the opposite
  // corner.
  const int starts[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  std::vector<PlannedPoint> points;
  for (const auto& start : starts) {
    Eigen::Vector3d from, to;
    for (int k = 0; k < 2; ++k) {
      from[k] = start[k] == 0 ? ws.min[k] : ws.max[k];
      to[k] = start[k] == 0 ? ws.max[k] : ws.min[k];
    }
    from.z() = ws.min.z();
    to.z() = ws.max.z();
    for (int i = 0; i < points_per_diagonal; ++i) {
      const double t = static_cast<double>(i) / (points_per_diagonal - 1);
      PlannedPoint p;
      p.id = PointId(points.size());
      for (int k = 0; k < 3; ++k) {
        p.nominal[k] = i == 0 ? from[k] : i == points_per_diagonal - 1 ? to[k]
                                                                       : RoundToMicrometre(from[k] + t * (to[k] - from[k]));
      }
      points.push_back(std::move(p));
    }
  }
  SetApproach(points);
  return points;
}

std::string GCodeProgram(const std::vector<PlannedPoint>& points, double dwell_s, double feed_mm_min) {
  if (!std::isfinite(dwell_s) || dwell_s < 0.0) {
    throw std::invalid_argument(fmt::format("dwell must be a non-negative number of seconds, not {}", dwell_s));
  }
  if (!std::isfinite(feed_mm_min)) throw std::invalid_argument("feed must be a finite number of mm/min");
  const bool rapid_only = feed_mm_min <= 0.0;
  std::string out = "%\n";
  out += fmt::format("(FVM VOLUMETRIC VERIFICATION: {} POINTS, DWELL {} S, {})\n", points.size(), FormatShortest(dwell_s),
                     rapid_only ? std::string("RAPID MOVES") : fmt::format("FEED {} MM/MIN", FormatShortest(feed_mm_min)));
  out += "(G4 P IS IN SECONDS HERE; ON A CONTROL THAT READS P AS MILLISECONDS USE G4 X)\n";
  out += "G90 G21 G17 G94\n";
  for (size_t i = 0; i < points.size(); ++i) {
    const PlannedPoint& p = points[i];
    const std::string xyz = fmt::format("X{} Y{} Z{}", FormatFixed(p.nominal.x(), 3), FormatFixed(p.nominal.y(), 3),
                                        FormatFixed(p.nominal.z(), 3));
    // Comments must not hold parentheses; ids from the planners never do, others are cleaned.
    std::string comment = p.id + (p.approach.empty() ? "" : " " + p.approach);
    std::replace(comment.begin(), comment.end(), '(', '[');
    std::replace(comment.begin(), comment.end(), ')', ']');
    std::replace(comment.begin(), comment.end(), '\n', ' ');
    if (i == 0 || rapid_only) {
      out += fmt::format("G0 {} ({})\n", xyz, comment);
    } else {
      out += fmt::format("G1 {}{} ({})\n", xyz, i == 1 ? " F" + FormatShortest(feed_mm_min) : "", comment);
    }
    out += fmt::format("G4 P{}\n", FormatShortest(dwell_s));
  }
  out += "M30\n%\n";
  return out;
}

Eigen::Vector3d VolumetricErrorVector(const stage::AxisChain& chain, const MachineTruth& truth, const Eigen::Vector3d& q) {
  stage::AxisChain machine = chain;
  machine.instrument.reset();
  double e[stage::kNumErrorTerms];
  TermValuesAt(truth, q, e);
  const double zero[stage::kNumErrorTerms] = {};
  return stage::ChainForward(machine, e, q) - stage::ChainForward(machine, zero, q);
}

double VolumetricErrorMm(const stage::AxisChain& chain, const MachineTruth& truth, const Eigen::Vector3d& q) {
  return VolumetricErrorVector(chain, truth, q).norm();
}

stage::ResidualSummary VolumetricErrorSummary(const stage::AxisChain& chain, const MachineTruth& truth,
                                              const std::vector<PlannedPoint>& points) {
  std::vector<Eigen::Vector3d> errors;
  errors.reserve(points.size());
  for (const PlannedPoint& p : points) errors.push_back(VolumetricErrorVector(chain, truth, p.nominal));
  return stage::Summarize(errors);
}

MachineTruth RandomMachineTruth(const stage::AxisChain& chain, const Workspace& ws, std::uint64_t seed,
                                double mean_error_um) {
  ws.Check();
  if (!(mean_error_um > 0.0) || !std::isfinite(mean_error_um) || mean_error_um > 100'000.0) {
    throw std::invalid_argument(fmt::format("mean volumetric error must be > 0 and at most 100000 um, not {}",
                                            mean_error_um));
  }
  MachineTruth truth;
  truth.workspace = ws;
  Random random(seed);
  for (int t = 0; t < stage::kNumErrorTerms; ++t) {
    TermTruth& term = truth.terms[static_cast<size_t>(t)];
    const stage::ErrorTerm& info = stage::GetErrorTerm(t);
    if (info.kind == stage::ErrorKind::kSquareness) {
      term.poly[0] = 20e-6 * random.Normal();
      continue;
    }
    const int k = static_cast<int>(info.axis);
    const double travel = ws.max[k] - ws.min[k];
    const bool positioning = info.kind == stage::ErrorKind::kTranslation && info.component == k;
    // rad for rotations; mm for translations (20 or 10 um per metre of travel).
    const double size = info.kind == stage::ErrorKind::kRotation ? 20e-6 : (positioning ? 20e-6 : 10e-6) * travel;
    // A cubic in x = u / travel: size * (g1 x + g2 x^2 + g3 x^3), higher powers smaller, as measured machines show.
    const double weights[4] = {0.0, 1.0, 0.5, 0.3};
    for (int p = 1; p <= 3; ++p) term.poly[static_cast<size_t>(p)] = size * weights[p] * random.Normal() / std::pow(travel, p);
    term.sine_amplitude = (positioning ? 0.08 : 0.25) * size * (0.5 + random.Uniform());
    term.sine_pitch_mm = positioning ? 10.0 + 30.0 * random.Uniform() : travel * (0.3 + 0.5 * random.Uniform());
    term.sine_phase_rad = 2.0 * kPi * random.Uniform();
    term.poly[0] = -term.sine_amplitude * std::sin(term.sine_phase_rad);  // zero at the origin
  }
  // Scale to the requested mean over an 11 x 11 x 11 mesh. The displacement is linear in the errors but for
  // products of small angles, so a few rounds converge to rounding.
  const std::vector<PlannedPoint> grid = PlanMesh(ws, (ws.max - ws.min) / 10.0);
  for (int round = 0; round < 6; ++round) {
    const double mean = VolumetricErrorSummary(chain, truth, grid).mean_um();
    if (!(mean > 0.0)) throw std::invalid_argument("the random machine has no volumetric error (degenerate chain?)");
    const double factor = mean_error_um / mean;
    if (std::abs(factor - 1.0) < 1e-12) break;
    for (TermTruth& term : truth.terms) {
      for (double& c : term.poly) c *= factor;
      term.sine_amplitude *= factor;
    }
  }
  return truth;
}

MachineTruth RandomMachineTruth(const Workspace& ws, std::uint64_t seed, double mean_error_um) {
  stage::AxisChain chain = stage::AxisChain::Parse("XFYZ");
  chain.tool_offset = Eigen::Vector3d(0.0, 0.0, 100.0);
  return RandomMachineTruth(chain, ws, seed, mean_error_um);
}

TrackerReadings SimulateTrackerReadings(const stage::AxisChain& chain, const MachineTruth& truth,
                                        const std::vector<PlannedPoint>& points, const stage::TrackerNoise& noise,
                                        std::uint64_t seed, TrackerReadings* noise_free) {
  if (!chain.instrument) {
    throw std::invalid_argument("SimulateTrackerReadings: the chain has no instrument pose (where the tracker sits)");
  }
  Random random(seed);
  TrackerReadings readings, truths;
  readings.points.reserve(points.size());
  truths.points.reserve(points.size());
  double e[stage::kNumErrorTerms];
  for (const PlannedPoint& p : points) {
    TermValuesAt(truth, p.nominal, e);
    TrackerReading reading;
    reading.id = p.id;
    reading.nominal = p.nominal;
    reading.approach = p.approach;
    reading.measured = stage::ChainForward(chain, e, p.nominal);
    truths.points.push_back(reading);
    // Three draws per point whatever the noise, so the sequence does not depend on the preset.
    const double n_range = random.Normal(), n_azimuth = random.Normal(), n_elevation = random.Normal();
    reading.measured = noise.Perturb(reading.measured, n_range, n_azimuth, n_elevation);
    readings.points.push_back(std::move(reading));
  }
  if (noise_free != nullptr) *noise_free = std::move(truths);
  return readings;
}

MultilaterationReadings SimulateMultilaterationReadings(const std::vector<Station>& stations,
                                                        const std::vector<std::pair<std::string, Eigen::Vector3d>>& targets,
                                                        const std::vector<Eigen::Vector3d>& nominal,
                                                        const stage::TrackerNoise& noise, std::uint64_t seed) {
  if (!nominal.empty() && nominal.size() != targets.size()) {
    throw std::invalid_argument("SimulateMultilaterationReadings: nominal and targets differ in number");
  }
  Random random(seed);
  MultilaterationReadings out;
  out.angles = true;
  out.nominal = !nominal.empty();
  out.rows.reserve(targets.size() * stations.size());
  for (size_t j = 0; j < targets.size(); ++j) {
    for (const Station& station : stations) {
      stage::Spherical s = stage::ToSpherical(targets[j].second - station.position);
      if (!(s.range_mm > 0.0)) {
        throw std::invalid_argument(fmt::format("point {} is at station {}", targets[j].first, station.name));
      }
      const double n_range = random.Normal(), n_azimuth = random.Normal(), n_elevation = random.Normal();
      if (!noise.IsNoiseFree()) {
        s.range_mm += noise.RangeSigmaMm(s.range_mm) * n_range;
        s.azimuth_rad = std::remainder(s.azimuth_rad + noise.azimuth_sigma_rad * n_azimuth, 2.0 * kPi);
        s.elevation_rad += noise.elevation_sigma_rad * n_elevation;
      }
      StationReadingRow row;
      row.id = targets[j].first;
      row.station = station.name;
      row.range_mm = s.range_mm;
      row.azimuth_rad = s.azimuth_rad;
      row.elevation_rad = s.elevation_rad;
      if (out.nominal) row.nominal = nominal[j];
      out.rows.push_back(std::move(row));
    }
  }
  return out;
}

std::vector<std::pair<std::string, Eigen::Vector3d>> TrueToolPoints(const stage::AxisChain& chain, const MachineTruth& truth,
                                                                    const std::vector<PlannedPoint>& points) {
  stage::AxisChain machine = chain;
  machine.instrument.reset();
  std::vector<std::pair<std::string, Eigen::Vector3d>> out;
  out.reserve(points.size());
  double e[stage::kNumErrorTerms];
  for (const PlannedPoint& p : points) {
    TermValuesAt(truth, p.nominal, e);
    out.emplace_back(p.id, stage::ChainForward(machine, e, p.nominal));
  }
  return out;
}

}  // namespace fvm::artefacts

