// stage/multilateration.h against a separately written least-squares solution of the same readings (plain
// Gauss-Newton with central-difference derivatives, its own frame and weights), the self-calibration's frame,
// the unobservable directions of too few stations, and the errors.
#include "stage/multilateration.h"
#include "stage/multilateration_start.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>

namespace fvm::stage {
namespace {

using Vec = Eigen::Vector3d;

// Points of a 2500 x 1500 x 1200 mm machine on a coarse mesh (the workspace of [IJSIMM 2016]).
std::vector<Vec> MeshPoints(int nx, int ny, int nz) {
  std::vector<Vec> out;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) out.emplace_back(2500.0 * i / (nx - 1), 1500.0 * j / (ny - 1), 1200.0 * k / (nz - 1));
  return out;
}

// Stations well spread around the machine (lines of sight about 90 deg apart from its centre), and a fourth.
std::vector<Vec> SpreadStations() {
  return {Vec(1250, -1699, -1132), Vec(3371, 1975, -1132), Vec(-871, 1975, -1132), Vec(-1309, -727, 1121)};
}
std::vector<Vec> ThreeSpreadStations() { return {Vec(1250, -1699, -1132), Vec(3371, 1975, -1132), Vec(-871, 1975, -1132)}; }

double RangeSigma(double range) { return 0.004 + 0.8e-6 * range; }  // the published preset, written out

MultilaterationProblem Readings(const std::vector<Vec>& stations, const std::vector<Vec>& points, std::uint64_t seed,
                                bool noisy = true) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal;
  MultilaterationProblem p;
  for (size_t i = 0; i < stations.size(); ++i) p.station_names.push_back(std::string(1, static_cast<char>('A' + i)));
  p.stations = stations;
  for (size_t j = 0; j < points.size(); ++j) {
    p.point_ids.push_back(std::string("P").append(std::to_string(j + 1)));
    for (size_t i = 0; i < stations.size(); ++i) {
      const Vec d = points[j] - stations[i];
      const double r = d.norm();
      StationReading m;
      m.point = static_cast<int>(j);
      m.station = static_cast<int>(i);
      m.range_mm = r + (noisy ? RangeSigma(r) * normal(engine) : 0.0);
      m.has_angles = true;
      m.azimuth_rad = std::atan2(d.y(), d.x()) + (noisy ? 24e-6 * normal(engine) : 0.0);
      m.elevation_rad = std::atan2(d.z(), std::hypot(d.x(), d.y())) + (noisy ? 24e-6 * normal(engine) : 0.0);
      p.readings.push_back(m);
    }
  }
  return p;
}

// The independent solution: Gauss-Newton with central differences on residuals(x).
Eigen::VectorXd GaussNewton(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& residuals, Eigen::VectorXd x) {
  for (int it = 0; it < 30; ++it) {
    const Eigen::VectorXd r = residuals(x);
    Eigen::MatrixXd j(r.size(), x.size());
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      const double h = 1e-5 * std::max(1.0, std::abs(x[k]));
      Eigen::VectorXd a = x, b = x;
      a[k] += h;
      b[k] -= h;
      j.col(k) = (residuals(a) - residuals(b)) / (2 * h);
    }
    const Eigen::VectorXd dx = j.colPivHouseholderQr().solve(-r);
    x += dx;
    if (dx.norm() < 1e-9) break;
  }
  return x;
}

double MeanError(const std::vector<Vec>& a, const std::vector<Vec>& b) {
  double sum = 0;
  for (size_t j = 0; j < a.size(); ++j) sum += (a[j] - b[j]).norm();
  return sum / static_cast<double>(a.size());
}

MultilaterationOptions Published() {
  MultilaterationOptions o;
  o.noise = TrackerNoise::Preset("published");
  return o;
}

TEST(Multilateration, KnownStationsWithinTenPercentOfAnIndependentSolution) {
  for (const auto& stations : {ThreeSpreadStations(), SpreadStations()}) {
    const std::vector<Vec> truth = MeshPoints(5, 4, 3);
    const MultilaterationProblem p = Readings(stations, truth, 11);
    const MultilaterationResult r = Multilaterate(p, Published());
    ASSERT_TRUE(r.converged);
    std::vector<Vec> independent;
    for (size_t j = 0; j < truth.size(); ++j) {
      const auto residuals = [&](const Eigen::VectorXd& x) {
        Eigen::VectorXd out(static_cast<Eigen::Index>(stations.size()));
        for (size_t i = 0; i < stations.size(); ++i) {
          const double range = p.readings[j * stations.size() + i].range_mm;
          out[static_cast<Eigen::Index>(i)] = ((Vec(x) - stations[i]).norm() - range) / RangeSigma(range);
        }
        return out;
      };
      independent.push_back(GaussNewton(residuals, truth[j] + Vec(0.3, -0.2, 0.4)));
    }
    const double ours = MeanError(r.points, truth), theirs = MeanError(independent, truth);
    EXPECT_NEAR(ours, theirs, 0.1 * theirs) << stations.size() << " stations";
    EXPECT_GT(ours, 1e-3);  // noise reached the points: the comparison means something
    // The uncertainties describe the errors: mean 3D u within a factor 1.5 of the rms error.
    double u = 0, e2 = 0;
    for (size_t j = 0; j < truth.size(); ++j) {
      u += std::sqrt(r.point_covariance[j].trace());
      e2 += (r.points[j] - truth[j]).squaredNorm();
    }
    u /= static_cast<double>(truth.size());
    const double rms = std::sqrt(e2 / static_cast<double>(truth.size()));
    EXPECT_GT(u, rms / 1.5);
    EXPECT_LT(u, rms * 1.5);
  }
}

// Truth in the 3-2-1 frame, written out here: station 1 at the origin, 2 on +x, 3 in the xy plane.
Eigen::Matrix<double, 3, 4> Frame(const std::vector<Vec>& s) {
  const Vec e1 = (s[1] - s[0]).normalized();
  const Vec v = (s[2] - s[0]) - (s[2] - s[0]).dot(e1) * e1;
  const Vec e2 = v.normalized(), e3 = e1.cross(e2);
  Eigen::Matrix<double, 3, 4> t;
  t.row(0) << e1.transpose(), -e1.dot(s[0]);
  t.row(1) << e2.transpose(), -e2.dot(s[0]);
  t.row(2) << e3.transpose(), -e3.dot(s[0]);
  return t;
}
Vec Apply(const Eigen::Matrix<double, 3, 4>& t, const Vec& p) { return t.leftCols<3>() * p + t.col(3); }

TEST(Multilateration, SelfCalibratedWithinTenPercentOfAnIndependentBundle) {
  const std::vector<Vec> stations = SpreadStations();
  const std::vector<Vec> truth = MeshPoints(4, 3, 3);
  MultilaterationProblem p = Readings(stations, truth, 5);
  // Start 20 mm away from the truth, as a tape would give it.
  for (size_t i = 0; i < stations.size(); ++i) p.stations[i] += Vec(20.0, -15.0, 10.0) * static_cast<double>(i);
  MultilaterationOptions o = Published();
  o.self_calibrate = true;
  const MultilaterationResult r = Multilaterate(p, o);
  ASSERT_TRUE(r.converged);
  EXPECT_TRUE(r.unobservable.empty());
  const auto t = Frame(stations);
  std::vector<Vec> truth_frame;
  for (const Vec& q : truth) truth_frame.push_back(Apply(t, q));

  // Unknowns: x2, x3, y3, x4, y4, z4, then the points.
  const size_t n = truth.size();
  const auto unpack_station = [](const Eigen::VectorXd& x, size_t i) -> Vec {
    if (i == 0) return Vec::Zero();
    if (i == 1) return Vec(x[0], 0, 0);
    if (i == 2) return Vec(x[1], x[2], 0);
    return Vec(x[3], x[4], x[5]);
  };
  const auto residuals = [&](const Eigen::VectorXd& x) {
    Eigen::VectorXd out(static_cast<Eigen::Index>(p.readings.size()));
    for (size_t k = 0; k < p.readings.size(); ++k) {
      const StationReading& m = p.readings[k];
      const Vec point = x.segment<3>(6 + 3 * m.point);
      out[static_cast<Eigen::Index>(k)] =
          ((point - unpack_station(x, static_cast<size_t>(m.station))).norm() - m.range_mm) / RangeSigma(m.range_mm);
    }
    return out;
  };
  Eigen::VectorXd x0(6 + 3 * n);
  const Vec s1 = Apply(t, stations[1]), s2 = Apply(t, stations[2]), s3 = Apply(t, stations[3]);
  x0.head<6>() << s1.x() + 0.5, s2.x() - 0.5, s2.y() + 0.5, s3.x(), s3.y() - 0.5, s3.z() + 0.5;
  for (size_t j = 0; j < n; ++j) x0.segment<3>(static_cast<Eigen::Index>(6 + 3 * j)) = truth_frame[j] + Vec(0.2, 0.1, -0.3);
  const Eigen::VectorXd x = GaussNewton(residuals, x0);
  std::vector<Vec> independent;
  for (size_t j = 0; j < n; ++j) independent.push_back(x.segment<3>(static_cast<Eigen::Index>(6 + 3 * j)));
  const double ours = MeanError(r.points, truth_frame), theirs = MeanError(independent, truth_frame);
  EXPECT_NEAR(ours, theirs, 0.1 * theirs);
  EXPECT_GT(ours, 1e-3);
  for (size_t i = 1; i < stations.size(); ++i) {
    EXPECT_LT((r.stations[i] - unpack_station(x, i)).norm(), 0.005) << "station " << i;
  }
}

TEST(Multilateration, SelfCalibrationRecoversTheStationsUpToTheFrame) {
  const std::vector<Vec> stations = SpreadStations();
  const std::vector<Vec> truth = MeshPoints(4, 3, 2);
  MultilaterationProblem p = Readings(stations, truth, 1, /*noisy=*/false);
  for (size_t i = 0; i < stations.size(); ++i) p.stations[i] += Vec(-30.0, 25.0, 40.0) * static_cast<double>(i % 2);
  for (const bool angles : {false, true}) {
    MultilaterationOptions o = Published();
    o.self_calibrate = true;
    o.use_angles = angles;
    const MultilaterationResult r = Multilaterate(p, o);
    ASSERT_TRUE(r.converged);
    const auto t = Frame(stations);
    for (size_t i = 0; i < stations.size(); ++i) EXPECT_LT((r.stations[i] - Apply(t, stations[i])).norm(), 1e-6) << i;
    for (size_t j = 0; j < truth.size(); ++j) EXPECT_LT((r.points[j] - Apply(t, truth[j])).norm(), 1e-6) << j;
    EXPECT_EQ(r.stations[1].y(), 0.0);
    EXPECT_EQ(r.stations[2].z(), 0.0);
  }
  // Without starting positions the angles start it.
  p.stations.clear();
  MultilaterationOptions o = Published();
  o.self_calibrate = true;
  const MultilaterationResult r = Multilaterate(p, o);
  EXPECT_LT((r.stations[3] - Apply(Frame(stations), stations[3])).norm(), 1e-6);
}

TEST(Multilateration, ThreeStationsLeaveThreeDirectionsWhateverThePoints) {
  const std::vector<Vec> three = ThreeSpreadStations();
  for (const auto& mesh : {MeshPoints(3, 2, 2), MeshPoints(6, 5, 4)}) {
    MultilaterationOptions o = Published();
    o.self_calibrate = true;
    const std::vector<std::string> lost = UnobservableStationParameters(Readings(three, mesh, 2), o);
    ASSERT_EQ(lost.size(), 3u);
    EXPECT_EQ(lost[0].substr(0, lost[0].find(':')), "station B x");
    EXPECT_EQ(lost[1].substr(0, lost[1].find(':')), "station C x");
    EXPECT_EQ(lost[2].substr(0, lost[2].find(':')), "station C y");
    // Multilaterate itself refuses: every point needs 4 stations to calibrate them.
    EXPECT_THROW(Multilaterate(Readings(three, mesh, 2), o), std::invalid_argument);
  }
  // Four stations and too few points (4 n ranges < 3 n + 6 unknowns): some directions are held and named.
  MultilaterationOptions o = Published();
  o.self_calibrate = true;
  const std::vector<Vec> few = {Vec(0, 0, 0), Vec(2500, 1500, 1200), Vec(2500, 0, 600), Vec(0, 1500, 300)};
  const MultilaterationResult r = Multilaterate(Readings(SpreadStations(), few, 3), o);
  EXPECT_GE(r.unobservable.size(), 2u);
  // Four stations and enough points: nothing is lost.
  EXPECT_TRUE(UnobservableStationParameters(Readings(SpreadStations(), MeshPoints(3, 3, 2), 3), o).empty());
}

TEST(Multilateration, ThreeStationsTakeThePointsSideFromTheAngles) {
  const std::vector<Vec> three = ThreeSpreadStations();
  const std::vector<Vec> truth = MeshPoints(3, 3, 2);
  MultilaterationProblem p = Readings(three, truth, 4, false);
  std::swap(p.stations[1], p.stations[2]);  // clockwise: the ranges alone would pick the mirror images
  std::swap(p.station_names[1], p.station_names[2]);
  for (StationReading& m : p.readings) m.station = m.station == 1 ? 2 : m.station == 2 ? 1 : 0;
  const MultilaterationResult r = Multilaterate(p, Published());
  for (size_t j = 0; j < truth.size(); ++j) EXPECT_LT((r.points[j] - truth[j]).norm(), 1e-6);
  for (StationReading& m : p.readings) m.has_angles = false;
  const MultilaterationResult mirrored = Multilaterate(p, Published());
  EXPECT_GT((mirrored.points[0] - truth[0]).norm(), 100.0);  // documented: the counter-clockwise side
}

TEST(Multilateration, BadInputIsNamed) {
  const std::vector<Vec> stations = SpreadStations();
  const auto message = [](const MultilaterationProblem& p, const MultilaterationOptions& o) {
    try {
      Multilaterate(p, o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // A point seen by two stations.
  MultilaterationProblem p = Readings(stations, MeshPoints(3, 2, 2), 1);
  p.readings.erase(std::remove_if(p.readings.begin(), p.readings.end(),
                                  [](const StationReading& m) { return m.point == 4 && m.station >= 2; }),
                   p.readings.end());
  EXPECT_NE(message(p, Published()).find("point P5 is seen by 2 station(s): A, B"), std::string::npos) << message(p, Published());
  // The same point is enough for known stations with 3, not for a self-calibration.
  p = Readings(stations, MeshPoints(3, 2, 2), 1);
  p.readings.erase(std::remove_if(p.readings.begin(), p.readings.end(),
                                  [](const StationReading& m) { return m.point == 2 && m.station == 3; }),
                   p.readings.end());
  EXPECT_NO_THROW(Multilaterate(p, Published()));
  MultilaterationOptions self = Published();
  self.self_calibrate = true;
  EXPECT_NE(message(p, self).find("point P3 is seen by 3 station(s)"), std::string::npos);
  // A station with no readings.
  p = Readings(stations, MeshPoints(3, 2, 2), 1);
  p.station_names.push_back("E");
  p.stations.push_back(Vec(5000, 0, 0));
  EXPECT_NE(message(p, Published()).find("station E has no readings"), std::string::npos);
  // Stations and points in one plane: ranges cannot fix the points across it.
  const std::vector<Vec> flat_stations = {Vec(-1000, -1000, 0), Vec(3500, -1000, 0), Vec(1250, 3000, 0)};
  const std::vector<Vec> flat_points = {Vec(0, 0, 0), Vec(2500, 0, 0), Vec(1250, 1500, 0)};
  EXPECT_NE(message(Readings(flat_stations, flat_points, 1, false), Published()).find("point P1 cannot be located: it lies in one plane"),
            std::string::npos)
      << message(Readings(flat_stations, flat_points, 1, false), Published());
  // A point read twice by one station.
  p = Readings(stations, MeshPoints(3, 2, 2), 1);
  p.readings.push_back(p.readings.front());
  EXPECT_NE(message(p, Published()).find("point P1 is read twice by station A"), std::string::npos);
}

TEST(Multilateration, ClosedFormTrilateration) {
  const std::vector<Vec> s = SpreadStations();
  const Vec p(700, 300, 900);
  std::vector<double> r;
  for (const Vec& q : s) r.push_back((p - q).norm());
  EXPECT_LT((TrilaterateClosedForm(s, r) - p).norm(), 1e-6);
  EXPECT_LT((TrilaterateClosedForm({s[0], s[1], s[2]}, {r[0], r[1], r[2]}) - p).norm(), 1e-6);
}

}  // namespace
}  // namespace fvm::stage
