#include "workflows/multilaterate.h"

#include <fmt/core.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/input_error.h"
#include "workflows/model_choice.h"

namespace fvm::workflows {

std::string Multilateration::Mode() const {
  return options.use_angles ? "bundle adjustment: ranges and angles" : "ranges only";
}

std::vector<artefacts::MultilateratedPoint> Multilateration::Points() const {
  std::vector<artefacts::MultilateratedPoint> points;
  for (size_t j = 0; j < result.points.size(); ++j) {
    points.push_back({problem.point_ids[j], result.points[j], result.point_covariance[j].diagonal().cwiseMax(0.0).cwiseSqrt()});
  }
  return points;
}

void MultilaterateOptions::Check() const {
  if (readings.empty()) throw InputError("no readings file: give READINGS.csv (id,station,range[,azimuth,elevation])");
  const std::vector<std::string> presets = stage::TrackerNoise::PresetNames();
  if (std::find(presets.begin(), presets.end(), tracker) == presets.end()) {
    throw InputError(fmt::format("--tracker {}: use one of {}", tracker, fmt::join(presets, ", ")));
  }
}

Multilateration Multilaterate(const MultilaterateOptions& args) {
  Multilateration m;
  m.data = artefacts::ReadMultilaterationReadings(args.readings);
  const artefacts::MultilaterationReadings& data = m.data;
  std::optional<std::vector<artefacts::Station>> stations;
  if (!args.stations.empty()) stations = artefacts::ReadStations(args.stations);
  if (!stations && !(args.self_calibrate && data.angles)) {
    throw InputError(fmt::format("{}: no stations: give --stations S.json (known positions, or starting values with "
                                 "--self-calibrate); a self-calibration without them starts from the angles, which "
                                 "this file does not have",
                                 args.readings));
  }
  if (args.angles && !data.angles) {
    throw InputError(fmt::format("{}: --angles needs azimuth,elevation columns (rad) beside id,station,range", args.readings));
  }

  // The problem: points in file order, stations in the stations file's order (or of first appearance).
  stage::MultilaterationProblem& problem = m.problem;
  std::map<std::string, int, std::less<>> point_index, station_index;
  if (stations) {
    for (const artefacts::Station& s : *stations) {
      station_index.emplace(s.name, static_cast<int>(problem.station_names.size()));
      problem.station_names.push_back(s.name);
      problem.stations.push_back(s.position);
    }
  }
  std::vector<int> readings_per_station(problem.station_names.size(), 0);
  for (const artefacts::StationReadingRow& r : data.rows) {
    auto s = station_index.find(r.station);
    if (s == station_index.end()) {
      if (stations) {
        throw InputError(fmt::format("{}:{}: point {}: station {} is not in {} (stations: {})", data.source, r.line, r.id,
                                     r.station, args.stations, JoinNames(problem.station_names)));
      }
      s = station_index.emplace(r.station, static_cast<int>(problem.station_names.size())).first;
      problem.station_names.push_back(r.station);
      readings_per_station.push_back(0);
    }
    auto p = point_index.find(r.id);
    if (p == point_index.end()) {
      p = point_index.emplace(r.id, static_cast<int>(problem.point_ids.size())).first;
      problem.point_ids.push_back(r.id);
    }
    ++readings_per_station[static_cast<size_t>(s->second)];
    stage::StationReading reading;
    reading.point = p->second;
    reading.station = s->second;
    reading.range_mm = r.range_mm;
    reading.has_angles = data.angles;
    reading.azimuth_rad = r.azimuth_rad;
    reading.elevation_rad = r.elevation_rad;
    problem.readings.push_back(reading);
  }
  for (size_t i = 0; i < readings_per_station.size(); ++i) {
    if (readings_per_station[i] == 0) {
      throw InputError(fmt::format("{}: station {} has no readings in {}; remove it or add its readings", args.stations,
                                   problem.station_names[i], args.readings));
    }
  }

  m.options.noise = stage::TrackerNoise::Preset(args.tracker);
  m.options.self_calibrate = args.self_calibrate;
  m.options.use_angles = args.angles;
  try {
    if (args.self_calibrate && problem.station_names.size() < 4) {
      const std::vector<std::string> lost = stage::UnobservableStationParameters(problem, m.options);
      std::string list;
      for (const std::string& u : lost) list += "\n  " + u;
      throw InputError(fmt::format("{}: self-calibration needs every point seen by at least 4 stations; with {} stations "
                                   "{} direction(s) of the stations stay unobservable whatever the number of points:{}\n"
                                   "add a station, or give the stations' positions and leave out --self-calibrate",
                                   args.readings, problem.station_names.size(), lost.size(), list));
    }
    m.result = stage::Multilaterate(problem, m.options);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: {}", args.readings, e.what()));
  }

  double u_sum = 0;
  for (size_t j = 0; j < m.result.points.size(); ++j) {
    const double u = m.result.point_covariance[j].diagonal().cwiseMax(0.0).cwiseSqrt().norm();
    u_sum += u;
    m.u_max_mm = std::max(m.u_max_mm, u);
  }
  m.u_mean_mm = u_sum / static_cast<double>(m.result.points.size());
  return m;
}

std::map<std::string, artefacts::ListedPoint, std::less<>> NominalCoordinates(const Multilateration& m,
                                                                              const std::string& nominal_file) {
  std::map<std::string, artefacts::ListedPoint, std::less<>> nominal;
  if (!nominal_file.empty()) {
    nominal = artefacts::PointsById(artefacts::ReadPointList(nominal_file));
  } else if (m.data.nominal) {
    for (const artefacts::StationReadingRow& r : m.data.rows) nominal.emplace(r.id, artefacts::ListedPoint{r.id, r.nominal, ""});
  }
  return nominal;
}

artefacts::TrackerReadings VerifyReadings(const Multilateration& m, const MultilaterateOptions& args,
                                          const std::map<std::string, artefacts::ListedPoint, std::less<>>& nominal,
                                          const std::string& nominal_file, const std::string& target) {
  if (nominal.empty()) {
    throw InputError(fmt::format("--verify-readings {}: needs each point's nominal machine coordinates: x,y,z columns in "
                                 "{} or --nominal POINTS.csv (id,x,y,z)",
                                 target, args.readings));
  }
  artefacts::TrackerReadings out;
  out.comments = {"fvm multilaterate: multilaterated points as tracker readings for fvm verify",
                  fmt::format("from {} ({}, {} stations{}); xt,yt,zt in the stations' frame (mm)", args.readings, m.Mode(),
                              m.problem.station_names.size(), args.self_calibrate ? ", self-calibrated" : "")};
  for (size_t j = 0; j < m.problem.point_ids.size(); ++j) {
    const auto it = nominal.find(m.problem.point_ids[j]);
    if (it == nominal.end()) {
      throw InputError(fmt::format("{}: point {} has no nominal coordinates there",
                                   nominal_file.empty() ? args.readings : nominal_file, m.problem.point_ids[j]));
    }
    artefacts::TrackerReading t;
    t.id = m.problem.point_ids[j];
    t.nominal = it->second.position;
    t.measured = m.result.points[j];
    t.covariance = m.result.point_covariance[j];  // fvm verify weighs each point by it
    t.approach = it->second.approach;
    out.points.push_back(std::move(t));
  }
  return out;
}

stage::ResidualSummary ErrorAgainstTruth(const Multilateration& m, const std::string& truth_file) {
  const auto truth = artefacts::PointsById(artefacts::ReadPointList(truth_file));
  std::vector<Eigen::Vector3d> errors;
  for (size_t j = 0; j < m.result.points.size(); ++j) {
    const auto it = truth.find(m.problem.point_ids[j]);
    if (it == truth.end()) throw InputError(fmt::format("{}: point {} is not there", truth_file, m.problem.point_ids[j]));
    errors.push_back(m.result.points[j] - it->second.position);
  }
  return stage::Summarize(errors);
}

}  // namespace fvm::workflows
