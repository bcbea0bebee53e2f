// The multilateration files (artefacts/io/multilateration_readings.h) and the multi-station simulation.
#include "artefacts/io/multilateration_readings.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "artefacts/simulation/machine_tool_simulation.h"
#include "tests/support/test_support.h"

namespace fvm::artefacts {
namespace {

using fvm::testing::InputErrorOf;
using ::testing::HasSubstr;

void Write(const std::filesystem::path& path, const std::string& text) { std::ofstream(path) << text; }

TEST(MultilaterationReadings, RoundTripIsBitExact) {
  testing::TempDir dir;
  MultilaterationReadings data;
  data.comments = {"three stations"};
  data.angles = true;
  data.nominal = true;
  StationReadingRow r;
  r.id = "P0001";
  r.station = "A, left";
  r.range_mm = 1234.5678901234567;
  r.azimuth_rad = -3.0000000000000004;
  r.elevation_rad = 0.1 + 0.2;
  r.nominal = Eigen::Vector3d(0, 1.0 / 3.0, 1200);
  data.rows = {r};
  r.station = "B";
  r.range_mm = 99'999.5;
  data.rows.push_back(r);
  WriteMultilaterationReadings(dir / "r.csv", data);
  const MultilaterationReadings back = ReadMultilaterationReadings(dir / "r.csv");
  ASSERT_EQ(back.rows.size(), 2u);
  EXPECT_TRUE(back.angles && back.nominal);
  EXPECT_EQ(back.comments, data.comments);
  EXPECT_EQ(back.rows[0].station, "A, left");
  EXPECT_EQ(back.rows[0].range_mm, data.rows[0].range_mm);
  EXPECT_EQ(back.rows[0].azimuth_rad, data.rows[0].azimuth_rad);
  EXPECT_EQ(back.rows[0].elevation_rad, data.rows[0].elevation_rad);
  EXPECT_EQ(back.rows[1].nominal, data.rows[1].nominal);
  EXPECT_EQ(back.rows[1].line, 4);
}

TEST(MultilaterationReadings, ErrorsNameFileLinePointAndStation) {
  testing::TempDir dir;
  const auto path = dir / "r.csv";
  Write(path, "# c\nid,station,range\nP1,A,3000\nP1,B,abc\n");
  EXPECT_THAT(InputErrorOf([&] { ReadMultilaterationReadings(path); }), HasSubstr("r.csv:4: point P1, station B: column 'range'"));
  Write(path, "id,station,range,azimuth,elevation\nP1,A,3000,0,1.6\n");
  EXPECT_THAT(InputErrorOf([&] { ReadMultilaterationReadings(path); }), HasSubstr("r.csv:2: point P1, station A: elevation = 1.6"));
  Write(path, "id,station,range,x,y\nP1,A,3000,0,0\n");
  EXPECT_THAT(InputErrorOf([&] { ReadMultilaterationReadings(path); }), HasSubstr("names 2 of the nominal columns"));
  Write(path, "id,station,range\nP1,,3000\n");
  EXPECT_THAT(InputErrorOf([&] { ReadMultilaterationReadings(path); }), HasSubstr("r.csv:2: point P1: the station is empty"));
  Write(path, "id,station,range\nP1,A,200000\n");
  EXPECT_THAT(InputErrorOf([&] { ReadMultilaterationReadings(path); }), HasSubstr("beyond 100 m"));
  Write(path, "id,station\nP1,A\n");
  EXPECT_THAT(InputErrorOf([&] { ReadMultilaterationReadings(path); }), HasSubstr("range"));
}

TEST(Stations, ReadAndRefused) {
  testing::TempDir dir;
  const auto path = dir / "s.json";
  Write(path, StationsJson({{"A", Eigen::Vector3d(0, 0, 0)}, {"B", Eigen::Vector3d(1.0 / 3.0, -2, 1e3)}}));
  const auto stations = ReadStations(path);
  ASSERT_EQ(stations.size(), 2u);
  EXPECT_EQ(stations[1].name, "B");
  EXPECT_EQ(stations[1].position, Eigen::Vector3d(1.0 / 3.0, -2, 1e3));
  Write(path, "{\"stations\": []}");
  EXPECT_THAT(InputErrorOf([&] { ReadStations(path); }), HasSubstr("s.json: the \"stations\" array is empty"));
  Write(path, "{\"stations\": [{\"name\": \"A\", \"x\": 0, \"y\": \"1\", \"z\": 0}]}");
  EXPECT_THAT(InputErrorOf([&] { ReadStations(path); }), HasSubstr("stations[0]: station A: no number \"y\""));
  Write(path, "[1, 2]");
  EXPECT_THAT(InputErrorOf([&] { ReadStations(path); }), HasSubstr("no \"stations\" array"));
  Write(path, "{\"stations\": [{\"name\": \"A\", \"x\": 0, \"y\": 0, \"z\": 2e5}]}");
  EXPECT_THAT(InputErrorOf([&] { ReadStations(path); }), HasSubstr("beyond 100 m"));
}

TEST(MultilaterationSimulation, SeededReadingsWithThePresetNoise) {
  const std::vector<Station> stations = {{"A", Eigen::Vector3d(0, 0, 0)}, {"B", Eigen::Vector3d(3000, 0, 0)},
                                         {"C", Eigen::Vector3d(0, 3000, 500)}};
  std::vector<std::pair<std::string, Eigen::Vector3d>> targets;
  for (int j = 0; j < 200; ++j) targets.emplace_back(std::string("P").append(std::to_string(j)), Eigen::Vector3d(1000 + j, 800, 600 + j));
  const stage::TrackerNoise noise = stage::TrackerNoise::Preset("published");
  const auto a = SimulateMultilaterationReadings(stations, targets, {}, noise, 7);
  const auto b = SimulateMultilaterationReadings(stations, targets, {}, noise, 7);
  const auto none = SimulateMultilaterationReadings(stations, targets, {}, stage::TrackerNoise::Preset("none"), 7);
  ASSERT_EQ(a.rows.size(), 600u);
  double sum2 = 0, sigma2 = 0;
  for (size_t k = 0; k < a.rows.size(); ++k) {
    EXPECT_EQ(a.rows[k].range_mm, b.rows[k].range_mm);
    const double d = a.rows[k].range_mm - none.rows[k].range_mm;
    sum2 += d * d;
    sigma2 += noise.RangeSigmaMm(none.rows[k].range_mm) * noise.RangeSigmaMm(none.rows[k].range_mm);
  }
  EXPECT_NEAR(std::sqrt(sum2 / sigma2), 1.0, 0.15);  // the range noise is a + b * L
  EXPECT_NEAR(none.rows[1].range_mm, (targets[0].second - stations[1].position).norm(), 1e-9);
}

}  // namespace
}  // namespace fvm::artefacts
