#include "stage/multilateration.h"

#include <fmt/core.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <limits>
#include <stdexcept>
#include <Eigen/LU>

#include "stage/linear_dependence.h"
#include "stage/network_plausibility.h"
#include "stage/pose.h"

namespace fvm::stage {
namespace {

constexpr double kPi = std::numbers::pi;

}  // namespace
// The closed-form start; `mirror` (when not null) receives the mirror image across the stations' plane when the
// ranges cannot tell the two apart (three stations, or all in one plane), else the same point.
Eigen::Vector3d Trilaterate(const std::vector<Eigen::Vector3d>& stations, const std::vector<double>& ranges,
                            Eigen::Vector3d* mirror);
namespace {

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
  double range_floor = 1e-3;  // a noise-free preset weighs ranges by 1 um
  double azimuth = 1e-6, elevation = 1e-6;
  const TrackerNoise* noise = nullptr;
  double Range(double range_mm) const { return noise == nullptr ? range_floor : RangeSigmaMm(*noise, range_mm); }
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

// Whitened residuals of one reading and their derivatives by the point (jp) and the station's rotation
// increment (jr); by the station's position they are -jp.
struct Linearised {
  int rows = 1;
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  Eigen::Matrix3d jp = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d jr = Eigen::Matrix3d::Zero();
};

Linearised Linearise(const StationReading& m, const Eigen::Vector3d& p, const Eigen::Vector3d& s,
                     const Eigen::Matrix3d& rotation, bool angles, const Sigmas& sigmas) {
  Linearised out;
  const Eigen::Vector3d q = rotation.transpose() * (p - s);
  const double r = std::max(q.norm(), 1e-12);
  Eigen::Matrix3d dq;  // rows: d(range, azimuth, elevation) / dq
  dq.setZero();
  const double sr = sigmas.Range(m.range_mm);
  out.r[0] = (r - m.range_mm) / sr;
  dq.row(0) = q.transpose() / r / sr;
  if (angles) {
    out.rows = 3;
    const double h2 = q.x() * q.x() + q.y() * q.y();
    const double h = std::sqrt(h2);
    if (h > 1e-9) {
      out.r[1] = std::remainder(std::atan2(q.y(), q.x()) - m.azimuth_rad, 2.0 * kPi) / sigmas.azimuth;
      dq.row(1) = Eigen::RowVector3d(-q.y() / h2, q.x() / h2, 0.0) / sigmas.azimuth;
      dq.row(2) = Eigen::RowVector3d(-q.x() * q.z() / (h * r * r), -q.y() * q.z() / (h * r * r), h / (r * r)) /
                  sigmas.elevation;
    }
    out.r[2] = (std::atan2(q.z(), h) - m.elevation_rad) / sigmas.elevation;
  }
  out.jp = dq * rotation.transpose();
  out.jr = dq * Skew(q);
  return out;
}

struct Normal {
  Eigen::MatrixXd a;
  Eigen::VectorXd bg;
  std::vector<Eigen::Matrix3d> d;
  std::vector<Eigen::Vector3d> bp;
  std::vector<Eigen::MatrixXd> b;  // ng x 3 per point
  double cost = 0;
  int residuals = 0;
};

struct Problem {
  const MultilaterationProblem* problem = nullptr;
  const MultilaterationOptions* options = nullptr;
  Sigmas sigmas;
  std::vector<std::vector<int>> readings_of_point;
};

double Cost(const Problem& pr, const State& st) {
  double cost = 0;
  for (const StationReading& m : pr.problem->readings) {
    const Linearised l = Linearise(m, st.points[static_cast<size_t>(m.point)], st.stations[static_cast<size_t>(m.station)],
                                   st.rotations[static_cast<size_t>(m.station)], pr.options->use_angles, pr.sigmas);
    cost += l.r.head(l.rows).squaredNorm();
  }
  return cost;
}

Normal Build(const Problem& pr, const State& st, const Layout& layout) {
  const int ng = layout.size();
  const size_t np = st.points.size();
  Normal n;
  n.a = Eigen::MatrixXd::Zero(ng, ng);
  n.bg = Eigen::VectorXd::Zero(ng);
  n.d.assign(np, Eigen::Matrix3d::Zero());
  n.bp.assign(np, Eigen::Vector3d::Zero());
  n.b.assign(np, Eigen::MatrixXd::Zero(ng, 3));
  for (const StationReading& m : pr.problem->readings) {
    const size_t j = static_cast<size_t>(m.point), i = static_cast<size_t>(m.station);
    const Linearised l = Linearise(m, st.points[j], st.stations[i], st.rotations[i], pr.options->use_angles, pr.sigmas);
    const int rows = l.rows;
    const Eigen::MatrixXd jp = l.jp.topRows(rows);
    const Eigen::VectorXd r = l.r.head(rows);
    n.cost += r.squaredNorm();
    n.residuals += rows;
    n.d[j] += jp.transpose() * jp;
    n.bp[j] += jp.transpose() * r;
    std::array<std::pair<int, Eigen::Vector3d>, 6> cols;
    int count = 0;
    for (int c = 0; c < 3; ++c) {
      if (layout.position[i][static_cast<size_t>(c)] >= 0) {
        Eigen::Vector3d col = Eigen::Vector3d::Zero();
        col.head(rows) = -l.jp.topRows(rows).col(c);
        cols[static_cast<size_t>(count++)] = {layout.position[i][static_cast<size_t>(c)], col};
      }
      if (layout.rotation[i][static_cast<size_t>(c)] >= 0) {
        Eigen::Vector3d col = Eigen::Vector3d::Zero();
        col.head(rows) = l.jr.topRows(rows).col(c);
        cols[static_cast<size_t>(count++)] = {layout.rotation[i][static_cast<size_t>(c)], col};
      }
    }
    Eigen::Vector3d rr = Eigen::Vector3d::Zero();
    rr.head(rows) = r;
    Eigen::Matrix3d jp3 = Eigen::Matrix3d::Zero();
    jp3.topRows(rows) = jp;
    for (int a = 0; a < count; ++a) {
      const auto& [ia, ca] = cols[static_cast<size_t>(a)];
      n.bg[ia] += ca.dot(rr);
      n.b[j].row(ia) += ca.transpose() * jp3;
      for (int b = 0; b < count; ++b) n.a(ia, cols[static_cast<size_t>(b)].first) += ca.dot(cols[static_cast<size_t>(b)].second);
    }
  }
  return n;
}

// The Schur complement of the points in the (damped) normal equations: S = A - sum B D^-1 B^T.
Eigen::MatrixXd Schur(const Normal& n, double lambda, std::vector<Eigen::Matrix3d>* d_inverse) {
  const Eigen::Index ng = n.a.rows();
  Eigen::MatrixXd s = n.a;
  s.diagonal() += lambda * n.a.diagonal();
  d_inverse->resize(n.d.size());
  for (size_t j = 0; j < n.d.size(); ++j) {
    Eigen::Matrix3d d = n.d[j];
    d.diagonal() += lambda * n.d[j].diagonal();
    (*d_inverse)[j] = d.inverse();
    if (ng > 0) s -= n.b[j] * (*d_inverse)[j] * n.b[j].transpose();
  }
  return s;
}

bool Step(const Normal& n, double lambda, State* st, const Layout& layout) {
  std::vector<Eigen::Matrix3d> dinv;
  const Eigen::MatrixXd s = Schur(n, lambda, &dinv);
  Eigen::VectorXd dg = Eigen::VectorXd::Zero(layout.size());
  if (layout.size() > 0) {
    Eigen::VectorXd rhs = -n.bg;
    for (size_t j = 0; j < n.d.size(); ++j) rhs += n.b[j] * (dinv[j] * n.bp[j]);
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(s);
    if (ldlt.info() != Eigen::Success) return false;
    dg = ldlt.solve(rhs);
  }
  if (!dg.allFinite()) return false;
  for (size_t j = 0; j < n.d.size(); ++j) {
    Eigen::Vector3d rhs = -n.bp[j];
    if (layout.size() > 0) rhs -= n.b[j].transpose() * dg;
    const Eigen::Vector3d dp = dinv[j] * rhs;
    if (!dp.allFinite()) return false;
    st->points[j] += dp;
  }
  for (size_t i = 0; i < st->stations.size(); ++i) {
    Eigen::Vector3d rot = Eigen::Vector3d::Zero();
    for (size_t c = 0; c < 3; ++c) {
      if (layout.position[i][c] >= 0) st->stations[i][static_cast<Eigen::Index>(c)] += dg[layout.position[i][c]];
      if (layout.rotation[i][c] >= 0) rot[static_cast<Eigen::Index>(c)] = dg[layout.rotation[i][c]];
    }
    if (rot.norm() > 0) st->rotations[i] = st->rotations[i] * Eigen::AngleAxisd(rot.norm(), rot.normalized()).toRotationMatrix();
  }
  return true;
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

// The best rotation of each station taking its Cartesian readings onto the directions to `points`, and what is
// left: the sum of squared misfits (mm^2) over all stations.
double RotationMisfit(const MultilaterationProblem& p, const std::vector<Eigen::Vector3d>& stations,
                      const std::vector<Eigen::Vector3d>& points, std::vector<Eigen::Matrix3d>* rotations = nullptr) {
  double misfit = 0;
  if (rotations != nullptr) rotations->assign(stations.size(), Eigen::Matrix3d::Identity());
  for (size_t i = 0; i < stations.size(); ++i) {
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    for (const StationReading& r : p.readings) {
      if (static_cast<size_t>(r.station) != i) continue;
      const Eigen::Vector3d local = FromSpherical({r.range_mm, r.azimuth_rad, r.elevation_rad});
      h += local * (points[static_cast<size_t>(r.point)] - stations[i]).transpose();
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d fix = Eigen::Matrix3d::Identity();
    fix(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    const Eigen::Matrix3d rotation = svd.matrixV() * fix * svd.matrixU().transpose();
    if (rotations != nullptr) (*rotations)[i] = rotation;
    for (const StationReading& r : p.readings) {
      if (static_cast<size_t>(r.station) != i) continue;
      const Eigen::Vector3d local = FromSpherical({r.range_mm, r.azimuth_rad, r.elevation_rad});
      misfit += (rotation * local - (points[static_cast<size_t>(r.point)] - stations[i])).squaredNorm();
    }
  }
  return misfit;
}

struct Prepared {
  Problem pr;
  State state;
};

Prepared Prepare(const MultilaterationProblem& p, const MultilaterationOptions& o, bool check_counts) {
  o.Check();
  Prepared out;
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
    if (any && RotationMisfit(p, st.stations, other) < RotationMisfit(p, st.stations, st.points)) st.points = other;
  }
  if (o.use_angles) RotationMisfit(p, st.stations, st.points, &st.rotations);
  return out;
}

// Throws naming the first point whose block cannot be inverted: its lines of sight and stations in one plane.
void CheckPointBlocks(const Problem& pr, const Normal& n) {
  for (size_t j = 0; j < n.d.size(); ++j) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(n.d[j]);
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
  const Eigen::MatrixXd s = Schur(n, 0.0, &dinv);
  const Eigen::Index ng = s.rows();
  // Scale each parameter to a unit column of the whole Jacobian: S_ii / A_ii is the share of the parameter's
  // effect the points leave unexplained (squared).
  Eigen::VectorXd scale(ng);
  for (Eigen::Index i = 0; i < ng; ++i) scale[i] = n.a(i, i) > 0 ? 1.0 / std::sqrt(n.a(i, i)) : 0.0;
  const Eigen::MatrixXd scaled = scale.asDiagonal() * s * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (scaled + scaled.transpose()));
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
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(utu);
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

void ThreeTwoOneFrame(const std::vector<Eigen::Vector3d>& stations, Eigen::Matrix3d* rotation, Eigen::Vector3d* translation) {
  if (stations.size() < 3) throw std::invalid_argument("the 3-2-1 frame needs three stations");
  const Eigen::Vector3d d1 = stations[1] - stations[0], d2 = stations[2] - stations[0];
  const Eigen::Vector3d e1 = d1.normalized();
  const Eigen::Vector3d v = d2 - d2.dot(e1) * e1;
  if (!(d1.norm() > 0) || !(v.norm() > 1e-9 * std::max(d1.norm(), d2.norm()))) {
    throw std::invalid_argument("stations 1, 2 and 3 lie on one line (or coincide): they cannot define the frame "
                                "(station 1 at the origin, 2 on x, 3 in the xy plane); reorder the stations");
  }
  const Eigen::Vector3d e2 = v.normalized();
  const Eigen::Vector3d e3 = e1.cross(e2);
  rotation->row(0) = e1.transpose();
  rotation->row(1) = e2.transpose();
  rotation->row(2) = e3.transpose();
  *translation = -(*rotation) * stations[0];
}

Eigen::Vector3d TrilaterateClosedForm(const std::vector<Eigen::Vector3d>& stations, const std::vector<double>& ranges) {
  return Trilaterate(stations, ranges, nullptr);
}

Eigen::Vector3d Trilaterate(const std::vector<Eigen::Vector3d>& stations, const std::vector<double>& ranges,
                            Eigen::Vector3d* mirror) {
  const size_t n = stations.size();
  if (n < 3 || ranges.size() != n) throw std::invalid_argument("trilateration needs three or more stations with a range each");
  const Eigen::Index rows = static_cast<Eigen::Index>(n - 1);
  Eigen::MatrixXd a(rows, 3);
  Eigen::VectorXd b(rows);
  for (size_t i = 1; i < n; ++i) {
    const Eigen::Vector3d d = stations[i] - stations[0];
    a.row(static_cast<Eigen::Index>(i - 1)) = 2.0 * d.transpose();
    b[static_cast<Eigen::Index>(i - 1)] = ranges[0] * ranges[0] - ranges[i] * ranges[i] + d.squaredNorm();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV | Eigen::ComputeThinU);
  const Eigen::VectorXd sv = svd.singularValues();
  if (n >= 4 && sv.size() == 3 && sv[2] > 1e-6 * sv[0]) {
    const Eigen::Vector3d p = stations[0] + svd.solve(b);
    if (mirror != nullptr) *mirror = p;
    return p;
  }
  // In the stations' plane, then the height above it.
  const Eigen::Matrix<double, 3, 2> plane = svd.matrixV().leftCols(2);
  Eigen::Vector3d normal = svd.matrixV().col(2);
  const Eigen::Vector2d in_plane = (a * plane).colPivHouseholderQr().solve(b);
  const Eigen::Vector3d x = plane * in_plane;
  double h2 = 0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = stations[i] - stations[0];
    h2 += ranges[i] * ranges[i] - (x - d).squaredNorm();
  }
  h2 /= static_cast<double>(n);
  // The side: where (s2 - s1) x (s3 - s1) of the first three stations points (they appear counter-clockwise from
  // the point); with those on one line, towards +z, +y or +x.
  const Eigen::Vector3d n0 = (stations[1] - stations[0]).cross(stations[2] - stations[0]);
  const double eps = 1e-9;
  const bool flip = n0.norm() > 1e-9 * (stations[1] - stations[0]).squaredNorm() ? normal.dot(n0) < 0
                    : std::abs(normal.z()) > eps                                 ? normal.z() < 0
                    : std::abs(normal.y()) > eps                                 ? normal.y() < 0
                                                                                 : normal.x() < 0;
  if (flip) normal = -normal;
  const double h = std::sqrt(std::max(0.0, h2));
  if (mirror != nullptr) *mirror = stations[0] + x - h * normal;
  return stations[0] + x + h * normal;
}

std::vector<Eigen::Vector3d> StartStationsFromAngles(const MultilaterationProblem& p) {
  const size_t m = p.station_names.size(), np = p.point_ids.size();
  // Cartesian reading of each point by each station (NaN when not read).
  std::vector<std::vector<Eigen::Vector3d>> local(m, std::vector<Eigen::Vector3d>(np, Eigen::Vector3d::Constant(NAN)));
  for (const StationReading& r : p.readings) {
    if (!r.has_angles) {
      throw std::invalid_argument("starting stations from the angles needs azimuth and elevation in every reading");
    }
    local[static_cast<size_t>(r.station)][static_cast<size_t>(r.point)] = FromSpherical({r.range_mm, r.azimuth_rad, r.elevation_rad});
  }
  std::vector<Eigen::Vector3d> out(m, Eigen::Vector3d::Zero());
  for (size_t i = 1; i < m; ++i) {
    std::vector<Eigen::Vector3d> from, to;
    for (size_t j = 0; j < np; ++j) {
      if (local[i][j].allFinite() && local[0][j].allFinite()) {
        from.push_back(local[i][j]);
        to.push_back(local[0][j]);
      }
    }
    Eigen::Vector3d cf = Eigen::Vector3d::Zero(), ct = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < from.size(); ++k) {
      cf += from[k];
      ct += to[k];
    }
    if (from.size() < 3) {
      throw std::invalid_argument(fmt::format("station {} shares {} points with station {}: a start from the angles "
                                              "needs 3; give starting positions (--stations)",
                                              p.station_names[i], from.size(), p.station_names[0]));
    }
    cf /= static_cast<double>(from.size());
    ct /= static_cast<double>(from.size());
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    for (size_t k = 0; k < from.size(); ++k) h += (from[k] - cf) * (to[k] - ct).transpose();
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
    if (!(svd.singularValues()[1] > 1e-9 * svd.singularValues()[0])) {
      throw std::invalid_argument(fmt::format("the points station {} shares with station {} lie on one line: a start "
                                              "from the angles needs them spread; give starting positions (--stations)",
                                              p.station_names[i], p.station_names[0]));
    }
    Eigen::Matrix3d fix = Eigen::Matrix3d::Identity();
    fix(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    const Eigen::Matrix3d r = svd.matrixV() * fix * svd.matrixU().transpose();
    out[i] = ct - r * cf;  // where station i's origin lands in station 1's frame
  }
  return out;
}

std::vector<std::string> UnobservableStationParameters(const MultilaterationProblem& problem,
                                                       const MultilaterationOptions& options) {
  const Prepared prep = Prepare(problem, options, false);
  return Unobservable(prep.pr, prep.state, MakeLayout(problem, options, {}));
}

MultilaterationResult Multilaterate(const MultilaterationProblem& problem, const MultilaterationOptions& options) {
  CheckRangesSpanANetwork(problem, options);
  Prepared prep = Prepare(problem, options, true);
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

  double lambda = 1e-4;
  double cost = Cost(pr, st);
  for (int it = 0; it < options.max_iterations; ++it) {
    result.iterations = it + 1;
    const Normal n = Build(pr, st, layout);
    bool accepted = false;
    State trial;
    double trial_cost = cost;
    for (int attempt = 0; attempt < 20 && !accepted; ++attempt) {
      trial = st;
      if (Step(n, lambda, &trial, layout)) {
        trial_cost = Cost(pr, trial);
        if (std::isfinite(trial_cost) && trial_cost <= cost) {
          accepted = true;
          break;
        }
      }
      lambda *= 10.0;
    }
    if (!accepted) {  // no step lowers the cost: a minimum to rounding
      result.converged = true;
      break;
    }
    double largest = 0;
    for (size_t j = 0; j < st.points.size(); ++j) largest = std::max(largest, (trial.points[j] - st.points[j]).norm());
    for (size_t i = 0; i < st.stations.size(); ++i) {
      largest = std::max(largest, (trial.stations[i] - st.stations[i]).norm());
      largest = std::max(largest, 1e3 * (trial.rotations[i] - st.rotations[i]).norm());
    }
    const double drop = cost - trial_cost;
    st = std::move(trial);
    cost = trial_cost;
    lambda = std::max(lambda / 10.0, 1e-12);
    if (largest < 1e-9 || drop <= 1e-14 * cost) {
      result.converged = true;
      break;
    }
  }

  // Covariance (a priori) and summaries at the solution.
  const Normal n = Build(pr, st, layout);
  CheckPointBlocks(pr, n);
  std::vector<Eigen::Matrix3d> dinv;
  const Eigen::MatrixXd s = Schur(n, 0.0, &dinv);
  Eigen::MatrixXd cov_g = Eigen::MatrixXd::Zero(layout.size(), layout.size());
  if (layout.size() > 0) cov_g = s.ldlt().solve(Eigen::MatrixXd::Identity(layout.size(), layout.size()));
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
