#include "stage/multilateration.h"

#include <ceres/ceres.h>
#include <fmt/core.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <tuple>

#include "core/dense_decomposition.h"
#include "stage/linear_dependence.h"
#include "stage/multilateration_start.h"
#include "stage/network_plausibility.h"
#include "stage/station_reading_cost.h"

namespace fvm::stage {
namespace {

constexpr double kPi = std::numbers::pi;

// Which station parameters are estimated: global index per coordinate, -1 when held.
struct Layout {
  std::vector<std::array<int, 3>> position;
  std::vector<std::array<int, 3>> rotation;
  std::vector<std::string> names;
  int size() const { return static_cast<int>(names.size()); }
};

struct State {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> stations;
  std::vector<Eigen::Matrix3d> rotations;
};

struct Sigmas {
  const TrackerNoise* noise = nullptr;
  double azimuth = 1e-6, elevation = 1e-6;  // a noise-free preset weighs angles by 1 urad
  ReadingSigmas Of(const StationReading& m) const { return {RangeSigmaMm(*noise, m.range_mm), azimuth, elevation}; }
};

Sigmas SigmasOf(const TrackerNoise& noise) {
  Sigmas s;
  s.noise = &noise;
  if (!noise.IsNoiseFree()) {
    s.azimuth = std::max(noise.azimuth_sigma_rad, 1e-12);
    s.elevation = std::max(noise.elevation_sigma_rad, 1e-12);
  }
  return s;
}

struct Problem {
  const MultilaterationProblem* problem = nullptr;
  const MultilaterationOptions* options = nullptr;
  Sigmas sigmas;
  std::vector<std::vector<int>> readings_of_point;
};

// The Gauss-Newton normal equations of the whitened residuals at a state, points and station parameters apart:
// A (station parameters, dense), D_j (3 x 3 per point), B_j (station parameters x 3 per point), the gradients bg
// and bp. What the rank analysis and the covariance need; the solve itself is Ceres'.
struct Normal {
  Eigen::MatrixXd a;
  Eigen::VectorXd bg;
  std::vector<Eigen::Matrix3d> d;
  std::vector<Eigen::Vector3d> bp;
  std::vector<Eigen::MatrixXd> b;  // ng x 3 per point
  double cost = 0;
  int residuals = 0;
};

Normal Build(const Problem& pr, const State& st, const Layout& layout) {
  const int ng = layout.size();
  const size_t np = st.points.size();
  const bool angles = pr.options->use_angles;
  Normal n;
  n.a = Eigen::MatrixXd::Zero(ng, ng);
  n.bg = Eigen::VectorXd::Zero(ng);
  n.d.assign(np, Eigen::Matrix3d::Zero());
  n.bp.assign(np, Eigen::Vector3d::Zero());
  n.b.assign(np, Eigen::MatrixXd::Zero(ng, 3));
  const Eigen::Vector3d no_turn = Eigen::Vector3d::Zero();
  for (const StationReading& m : pr.problem->readings) {
    const size_t j = static_cast<size_t>(m.point), i = static_cast<size_t>(m.station);
    const auto cost = StationReadingCost(m, pr.sigmas.Of(m), st.rotations[i], angles);
    // Row-major Jacobians of the residuals by the point, the station's position and its rotation increment; rows
    // past the cost's residuals stay zero and add nothing.
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> jp = Eigen::Matrix3d::Zero(), js = jp, jr = jp;
    Eigen::Vector3d r = Eigen::Vector3d::Zero();
    const double* parameters[] = {st.points[j].data(), st.stations[i].data(), no_turn.data()};
    double* jacobians[] = {jp.data(), js.data(), jr.data()};
    if (!cost->Evaluate(parameters, r.data(), jacobians)) throw std::logic_error("a station reading's cost failed");
    n.cost += r.squaredNorm();
    n.residuals += cost->num_residuals();
    n.d[j] += jp.transpose() * jp;
    n.bp[j] += jp.transpose() * r;
    // This reading's station-parameter columns: (global index, column of the Jacobian).
    std::array<std::pair<int, Eigen::Vector3d>, 6> cols;
    int count = 0;
    for (size_t c = 0; c < 3; ++c) {
      const Eigen::Index ci = static_cast<Eigen::Index>(c);
      if (layout.position[i][c] >= 0) cols[static_cast<size_t>(count++)] = {layout.position[i][c], js.col(ci)};
      if (angles && layout.rotation[i][c] >= 0) cols[static_cast<size_t>(count++)] = {layout.rotation[i][c], jr.col(ci)};
    }
    for (int x = 0; x < count; ++x) {
      const auto& [ix, cx] = cols[static_cast<size_t>(x)];
      n.bg[ix] += cx.dot(r);
      n.b[j].row(ix) += cx.transpose() * jp;
      for (int y = 0; y < count; ++y) n.a(ix, cols[static_cast<size_t>(y)].first) += cx.dot(cols[static_cast<size_t>(y)].second);
    }
  }
  return n;
}

// The Schur complement of the points in the normal equations, S = A - sum B D^-1 B^T, and each D^-1.
Eigen::MatrixXd Schur(const Normal& n, std::vector<Eigen::Matrix3d>* d_inverse) {
  const Eigen::Index ng = n.a.rows();
  Eigen::MatrixXd s = n.a;
  d_inverse->resize(n.d.size());
  for (size_t j = 0; j < n.d.size(); ++j) {
    (*d_inverse)[j] = n.d[j].inverse();
    if (ng > 0) s -= n.b[j] * (*d_inverse)[j] * n.b[j].transpose();
  }
  return s;
}

// A parameter block whose coordinates the layout holds (index -1) kept there: constant when all are.
void HoldCoordinates(ceres::Problem* problem, double* block, const std::array<int, 3>& index) {
  std::vector<int> held;
  for (int c = 0; c < 3; ++c) {
    if (index[static_cast<size_t>(c)] < 0) held.push_back(c);
  }
  if (held.size() == 3) {
    problem->SetParameterBlockConstant(block);
  } else if (!held.empty()) {
    problem->SetManifold(block, new ceres::SubsetManifold(3, held));
  }
}

// Levenberg-Marquardt (Ceres) on the whitened residuals of every reading, the points eliminated first (Schur
// complement: each point is a 3 x 3 block, the station parameters a small dense system). With known stations and
// ranges only, every point is its own 3-unknown solve. Each station's rotation moves by an increment that is
// folded into it afterwards. Returns the number of iterations and whether Ceres converged.
std::pair<int, bool> Solve(const Problem& pr, const Layout& layout, int max_iterations, State* st) {
  const bool angles = pr.options->use_angles;
  ceres::Problem problem;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (Eigen::Vector3d& p : st->points) {
    problem.AddParameterBlock(p.data(), 3);
    ordering->AddElementToGroup(p.data(), 0);
  }
  // Within a group Ceres orders the blocks by their addresses: the stations and the turns, two arrays, in groups of
  // their own, so that the reduced system's columns, and with them its rounding, do not depend on where the heap
  // put the two arrays (in a long-lived process, such as Python's, the last digits changed from call to call).
  std::vector<Eigen::Vector3d> turns(st->stations.size(), Eigen::Vector3d::Zero());
  for (size_t i = 0; i < st->stations.size(); ++i) {
    problem.AddParameterBlock(st->stations[i].data(), 3);
    HoldCoordinates(&problem, st->stations[i].data(), layout.position[i]);
    ordering->AddElementToGroup(st->stations[i].data(), 1);
    if (angles) {
      problem.AddParameterBlock(turns[i].data(), 3);
      HoldCoordinates(&problem, turns[i].data(), layout.rotation[i]);
      ordering->AddElementToGroup(turns[i].data(), 2);
    }
  }
  for (const StationReading& m : pr.problem->readings) {
    const size_t j = static_cast<size_t>(m.point), i = static_cast<size_t>(m.station);
    ceres::CostFunction* cost = StationReadingCost(m, pr.sigmas.Of(m), st->rotations[i], angles).release();
    if (angles) {
      problem.AddResidualBlock(cost, nullptr, st->points[j].data(), st->stations[i].data(), turns[i].data());
    } else {
      problem.AddResidualBlock(cost, nullptr, st->points[j].data(), st->stations[i].data());
    }
  }
  ceres::Solver::Options options;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.linear_solver_ordering = ordering;
  options.max_num_iterations = max_iterations;
  // Metrology wants the minimum to rounding: steps below a nanometre on metre coordinates, or no cost left to drop.
  options.function_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.gradient_tolerance = 1e-20;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  for (size_t i = 0; i < turns.size(); ++i) {
    const double angle = turns[i].norm();
    if (angle > 0) st->rotations[i] = st->rotations[i] * Eigen::AngleAxisd(angle, turns[i] / angle).toRotationMatrix();
  }
  return {summary.num_successful_steps + summary.num_unsuccessful_steps,
          summary.termination_type == ceres::CONVERGENCE};
}

std::string StationParameterName(const std::string& station, int c, bool rotation) {
  return rotation ? fmt::format("station {} rotation about {}", station, "xyz"[c])
                  : fmt::format("station {} {}", station, "xyz"[c]);
}

Layout MakeLayout(const MultilaterationProblem& p, const MultilaterationOptions& o, const std::vector<std::string>& held) {
  Layout l;
  const size_t m = p.station_names.size();
  l.position.assign(m, {-1, -1, -1});
  l.rotation.assign(m, {-1, -1, -1});
  const auto add = [&](const std::string& name) -> int {
    if (std::find(held.begin(), held.end(), name) != held.end()) return -1;
    l.names.push_back(name);
    return l.size() - 1;
  };
  for (size_t i = 0; i < m; ++i) {
    if (o.self_calibrate) {
      // 3-2-1: station 1 all held, station 2 only x free, station 3 x and y free.
      for (int c = 0; c < 3; ++c) {
        const bool free = (i == 1 && c == 0) || (i == 2 && c < 2) || i >= 3;
        if (free) l.position[i][static_cast<size_t>(c)] = add(StationParameterName(p.station_names[i], c, false));
      }
    }
    if (o.use_angles) {
      for (int c = 0; c < 3; ++c) l.rotation[i][static_cast<size_t>(c)] = add(StationParameterName(p.station_names[i], c, true));
    }
  }
  return l;
}

// Station readings of one point: positions and ranges (for the closed-form start and messages).
std::string StationList(const MultilaterationProblem& p, const std::vector<int>& readings) {
  std::string out;
  for (int k : readings) {
    if (!out.empty()) out += ", ";
    out += p.station_names[static_cast<size_t>(p.readings[static_cast<size_t>(k)].station)];
  }
  return out;
}

struct PreparedProblem {
  Problem pr;
  State state;
};

PreparedProblem Prepare(const MultilaterationProblem& p, const MultilaterationOptions& o, bool check_counts) {
  o.Check();
  PreparedProblem out;
  out.pr.problem = &p;
  out.pr.options = &o;
  out.pr.sigmas = SigmasOf(o.noise);
  const size_t m = p.station_names.size(), np = p.point_ids.size();
  if (m == 0) throw std::invalid_argument("no stations");
  if (np == 0) throw std::invalid_argument("no points");
  if (o.self_calibrate && m < 3) {
    throw std::invalid_argument(fmt::format("self-calibration needs at least 3 stations (4 to determine them); there are {}", m));
  }
  std::vector<std::vector<int>> of_point(np);
  std::vector<int> per_station(m, 0);
  std::vector<std::vector<int>> seen(np);
  for (size_t k = 0; k < p.readings.size(); ++k) {
    const StationReading& r = p.readings[k];
    if (r.point < 0 || static_cast<size_t>(r.point) >= np || r.station < 0 || static_cast<size_t>(r.station) >= m) {
      throw std::invalid_argument(fmt::format("reading {} refers to a point or station that does not exist", k + 1));
    }
    const std::string& id = p.point_ids[static_cast<size_t>(r.point)];
    const std::string& name = p.station_names[static_cast<size_t>(r.station)];
    if (!std::isfinite(r.range_mm) || r.range_mm <= 0) {
      throw std::invalid_argument(fmt::format("point {}, station {}: range {} mm is not a positive number", id, name, r.range_mm));
    }
    if (o.use_angles && !r.has_angles) {
      throw std::invalid_argument(fmt::format("point {}, station {}: no azimuth and elevation, which --angles needs", id, name));
    }
    auto& s = seen[static_cast<size_t>(r.point)];
    if (std::find(s.begin(), s.end(), r.station) != s.end()) {
      throw std::invalid_argument(fmt::format("point {} is read twice by station {}; keep one reading", id, name));
    }
    s.push_back(r.station);
    of_point[static_cast<size_t>(r.point)].push_back(static_cast<int>(k));
    ++per_station[static_cast<size_t>(r.station)];
  }
  for (size_t i = 0; i < m; ++i) {
    if (per_station[i] == 0) {
      throw std::invalid_argument(fmt::format("station {} has no readings; remove it from the stations or add its readings",
                                              p.station_names[i]));
    }
  }
  const int need = check_counts ? MinStationsPerPoint(o) : 3;
  for (size_t j = 0; j < np; ++j) {
    const int have = static_cast<int>(of_point[j].size());
    if (have < need) {
      throw std::invalid_argument(fmt::format(
          "point {} is seen by {} station(s){}{}; {} needs at least {}{}", p.point_ids[j], have,
          have > 0 ? ": " : "", StationList(p, of_point[j]), o.self_calibrate ? "self-calibration" : "a point from ranges",
          need, o.self_calibrate ? " (3 ranges only locate a point, they add nothing to the stations)" : " (three spheres meet in a point)"));
    }
  }
  // Stations in their own order, whatever the order of the readings: the side rule of the start names them so.
  for (std::vector<int>& k : of_point) {
    std::sort(k.begin(), k.end(), [&](int a, int b) {
      return p.readings[static_cast<size_t>(a)].station < p.readings[static_cast<size_t>(b)].station;
    });
  }
  out.pr.readings_of_point = of_point;

  State& st = out.state;
  if (p.stations.empty()) {
    const bool angles = std::all_of(p.readings.begin(), p.readings.end(), [](const StationReading& r) { return r.has_angles; });
    if (!o.self_calibrate || !angles) {
      throw std::invalid_argument("no station positions: give them (known) or, for a self-calibration, starting values");
    }
    st.stations = StartStationsFromAngles(p);
  } else {
    if (p.stations.size() != m) throw std::invalid_argument("the station positions and names differ in number");
    st.stations = p.stations;
  }
  for (size_t i = 0; i < m; ++i) {
    if (!st.stations[i].allFinite()) throw std::invalid_argument("station " + p.station_names[i] + ": position is not finite");
  }
  if (o.self_calibrate) {
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
    ThreeTwoOneFrame(st.stations, &r, &t);
    for (Eigen::Vector3d& s : st.stations) s = r * s + t;
    st.stations[0].setZero();  // exactly the frame, not its rounding
    st.stations[1].tail<2>().setZero();
    st.stations[2].z() = 0.0;
  }
  st.rotations.assign(m, Eigen::Matrix3d::Identity());
  st.points.resize(np);
  std::vector<Eigen::Vector3d> mirrors(np);
  for (size_t j = 0; j < np; ++j) {
    std::vector<Eigen::Vector3d> s;
    std::vector<double> ranges;
    for (int k : of_point[j]) {
      const StationReading& r = p.readings[static_cast<size_t>(k)];
      s.push_back(st.stations[static_cast<size_t>(r.station)]);
      ranges.push_back(r.range_mm);
    }
    st.points[j] = Trilaterate(s, ranges, &mirrors[j]);
  }
  // Readings with angles settle the side of points that ranges alone leave mirrored: the side whose directions a
  // rotation of each station matches best.
  const bool all_angles = std::all_of(p.readings.begin(), p.readings.end(), [](const StationReading& r) { return r.has_angles; });
  if (all_angles) {
    std::vector<Eigen::Vector3d> other = st.points;
    bool any = false;
    for (size_t j = 0; j < np; ++j) {
      if ((mirrors[j] - st.points[j]).norm() > 1e-9) {
        other[j] = mirrors[j];
        any = true;
      }
    }
    if (any && StationRotationMisfit(p, st.stations, other, nullptr) < StationRotationMisfit(p, st.stations, st.points, nullptr)) st.points = other;
  }
  if (o.use_angles) StationRotationMisfit(p, st.stations, st.points, &st.rotations);
  return out;
}

// Throws naming the first point whose block cannot be inverted: its lines of sight and stations in one plane.
void CheckPointBlocks(const Problem& pr, const Normal& n) {
  for (size_t j = 0; j < n.d.size(); ++j) {
    const auto eig = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>>(
        n.d[j], fmt::format("multilateration: the normal block of point {}", pr.problem->point_ids[j]));
    const Eigen::Vector3d ev = eig.eigenvalues();
    if (!(ev[0] > 1e-10 * ev[2])) {
      const MultilaterationProblem& p = *pr.problem;
      throw std::invalid_argument(fmt::format(
          "point {} cannot be located: it lies in one plane with the stations that see it ({}), so their ranges "
          "cannot fix it across that plane; move a station out of that plane or add one",
          p.point_ids[j], StationList(p, pr.readings_of_point[j])));
    }
  }
}

std::vector<std::string> Unobservable(const Problem& pr, const State& st, const Layout& layout) {
  std::vector<std::string> out;
  if (layout.size() == 0) return out;
  const Normal n = Build(pr, st, layout);
  CheckPointBlocks(pr, n);
  std::vector<Eigen::Matrix3d> dinv;
  const Eigen::MatrixXd s = Schur(n, &dinv);
  const Eigen::Index ng = s.rows();
  // Scale each parameter to a unit column of the whole Jacobian: S_ii / A_ii is the share of the parameter's
  // effect the points leave unexplained (squared).
  Eigen::VectorXd scale(ng);
  for (Eigen::Index i = 0; i < ng; ++i) scale[i] = n.a(i, i) > 0 ? 1.0 / std::sqrt(n.a(i, i)) : 0.0;
  const Eigen::MatrixXd scaled = scale.asDiagonal() * s * scale.asDiagonal();
  const auto eig = Decompose<Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>>(
      0.5 * (scaled + scaled.transpose()), "multilateration: the stations' and instruments' parameters (Schur complement)");
  Eigen::MatrixXd l = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose();
  const double tol = pr.options->rank_tolerance;
  for (Eigen::Index i = 0; i < ng; ++i) {
    if (!(scaled(i, i) > tol * tol)) l.col(i).setZero();
  }
  std::vector<int> order(static_cast<size_t>(ng));
  for (int i = 0; i < ng; ++i) order[static_cast<size_t>(i)] = i;
  for (const ColumnDependence& d : FindDependentColumns(l, order, tol)) {
    const std::string& name = layout.names[static_cast<size_t>(d.column)];
    if (d.on.empty()) {
      out.push_back(name + ": the points absorb it (their coordinates follow any change of it: as many ranges as "
                           "point coordinates)");
    } else {
      std::string on;
      for (const auto& [c, f] : d.on) {
        if (!on.empty()) on += " + ";
        on += fmt::format("{:.3g} * {}", f * scale[c] / scale[d.column],
                          layout.names[static_cast<size_t>(c)]);
      }
      out.push_back(name + ": same effect as " + on + " once the points adjust");
    }
  }
  return out;
}

NetworkGeometry Geometry(const Problem& pr, const State& st) {
  NetworkGeometry g;
  double sum = 0;
  int pairs = 0;
  g.min_angle_deg = 90.0;
  double pdop_sum = 0;
  for (size_t j = 0; j < st.points.size(); ++j) {
    std::vector<Eigen::Vector3d> u;
    for (int k : pr.readings_of_point[j]) {
      const int i = pr.problem->readings[static_cast<size_t>(k)].station;
      u.push_back((st.stations[static_cast<size_t>(i)] - st.points[j]).normalized());
    }
    Eigen::Matrix3d utu = Eigen::Matrix3d::Zero();
    for (size_t a = 0; a < u.size(); ++a) {
      utu += u[a] * u[a].transpose();
      for (size_t b = a + 1; b < u.size(); ++b) {
        double deg = std::acos(std::clamp(u[a].dot(u[b]), -1.0, 1.0)) * 180.0 / kPi;
        if (deg > 90.0) deg = 180.0 - deg;
        g.min_angle_deg = std::min(g.min_angle_deg, deg);
        g.max_angle_deg = std::max(g.max_angle_deg, deg);
        sum += deg;
        ++pairs;
      }
    }
    const auto lu = Decompose<Eigen::FullPivLU<Eigen::Matrix3d>>(utu, "multilateration: the geometry (PDOP) of a point");
    const double pdop = lu.isInvertible() ? std::sqrt(utu.inverse().trace()) : std::numeric_limits<double>::infinity();
    pdop_sum += pdop;
    g.max_pdop = std::max(g.max_pdop, pdop);
  }
  g.mean_angle_deg = pairs > 0 ? sum / pairs : 0.0;
  if (pairs == 0) g.min_angle_deg = 0;
  g.mean_pdop = pdop_sum / static_cast<double>(std::max<size_t>(1, st.points.size()));
  return g;
}

}  // namespace

void MultilaterationOptions::Check() const {
  if (max_iterations < 1) throw std::invalid_argument("max_iterations must be at least 1");
  if (!(rank_tolerance > 0.0 && rank_tolerance < 1.0)) throw std::invalid_argument("rank_tolerance must be in (0, 1)");
}

double RangeSigmaMm(const TrackerNoise& noise, double range_mm) {
  return noise.IsNoiseFree() ? 1e-3 : std::max(noise.RangeSigmaMm(range_mm), 1e-9);
}

int MinStationsPerPoint(const MultilaterationOptions& options) { return options.self_calibrate ? 4 : 3; }

std::vector<std::string> UnobservableStationParameters(const MultilaterationProblem& problem,
                                                       const MultilaterationOptions& options) {
  const PreparedProblem prep = Prepare(problem, options, false);
  return Unobservable(prep.pr, prep.state, MakeLayout(problem, options, {}));
}

MultilaterationResult Multilaterate(const MultilaterationProblem& problem, const MultilaterationOptions& options) {
  CheckRangesSpanANetwork(problem, options);
  PreparedProblem prep = Prepare(problem, options, true);
  const Problem& pr = prep.pr;
  State& st = prep.state;
  MultilaterationResult result;
  // Rank: hold what the readings cannot determine, at its start.
  std::vector<std::string> held;
  for (const std::string& u : Unobservable(pr, st, MakeLayout(problem, options, {}))) {
    result.unobservable.push_back(u);
    held.push_back(u.substr(0, u.find(':')));
  }
  const Layout layout = MakeLayout(problem, options, held);

  std::tie(result.iterations, result.converged) = Solve(pr, layout, options.max_iterations, &st);

  // Covariance (a priori) and summaries at the solution.
  const Normal n = Build(pr, st, layout);
  CheckPointBlocks(pr, n);
  std::vector<Eigen::Matrix3d> dinv;
  const Eigen::MatrixXd s = Schur(n, &dinv);
  Eigen::MatrixXd cov_g = Eigen::MatrixXd::Zero(layout.size(), layout.size());
  if (layout.size() > 0) {
    cov_g = Decompose<Eigen::LDLT<Eigen::MatrixXd>>(s, "multilateration: the covariance of the stations' parameters")
                .solve(Eigen::MatrixXd::Identity(layout.size(), layout.size()));
  }
  result.points = st.points;
  result.point_covariance.resize(st.points.size());
  for (size_t j = 0; j < st.points.size(); ++j) {
    Eigen::Matrix3d c = dinv[j];
    if (layout.size() > 0) c += dinv[j] * n.b[j].transpose() * cov_g * n.b[j] * dinv[j];
    result.point_covariance[j] = 0.5 * (c + c.transpose());
  }
  result.stations = st.stations;
  result.station_u.assign(st.stations.size(), Eigen::Vector3d::Zero());
  result.station_rotation.assign(st.stations.size(), Eigen::Vector3d::Zero());
  for (size_t i = 0; i < st.stations.size(); ++i) {
    for (size_t c = 0; c < 3; ++c) {
      const int g = layout.position[i][c];
      if (g >= 0) result.station_u[i][static_cast<Eigen::Index>(c)] = std::sqrt(std::max(0.0, cov_g(g, g)));
    }
    const Eigen::AngleAxisd aa(st.rotations[i]);
    result.station_rotation[i] = aa.angle() * aa.axis();
  }
  double sum2 = 0, sigmas2 = 0;
  for (const StationReading& m : problem.readings) {
    const Eigen::Vector3d q = st.rotations[static_cast<size_t>(m.station)].transpose() *
                              (st.points[static_cast<size_t>(m.point)] - st.stations[static_cast<size_t>(m.station)]);
    const double r = q.norm() - m.range_mm;
    result.range_residuals_mm.push_back(r);
    sum2 += r * r;
    sigmas2 += std::pow(r / RangeSigmaMm(options.noise, m.range_mm), 2);
  }
  result.range_rms_sigmas = std::sqrt(sigmas2 / static_cast<double>(std::max<size_t>(1, problem.readings.size())));
  result.range_rms_mm = std::sqrt(sum2 / static_cast<double>(std::max<size_t>(1, problem.readings.size())));
  const int dof = n.residuals - 3 * static_cast<int>(st.points.size()) - layout.size();
  result.weighted_rms = dof > 0 ? std::sqrt(n.cost / dof) : 0.0;
  result.geometry = Geometry(pr, st);
  CheckNetworkPlausible(problem, options, result);
  return result;
}

}  // namespace fvm::stage
