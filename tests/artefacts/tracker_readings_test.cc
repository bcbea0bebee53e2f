#include "artefacts/io/tracker_readings.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/input_error.h"
#include "tests/support/test_support.h"

namespace fvm::artefacts {
namespace {

using fvm::testing::InputErrorOf;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

TrackerReading Reading(const std::string& id, Eigen::Vector3d nominal, Eigen::Vector3d measured,
                       const std::string& approach = "") {
  TrackerReading r;
  r.id = id;
  r.nominal = nominal;
  r.measured = measured;
  r.approach = approach;
  return r;
}

TEST(TrackerReadings, CartesianRoundTripIsBitExact) {
  testing::TempDir dir;
  TrackerReadings data;
  data.comments = {"chain XFYZ, tool 0,0,100 mm", "tracker published, seed 1"};
  // Values with all 17 significant digits, a tiny one (the smallest normal double: a subnormal is refused as no
  // measurement, issue 44), a negative zero's neighbour and the 100 m bound.
  data.points = {Reading("P0001", {0, 0, 0}, {-1234.5678901234567, 2345.0000000000005, -1e-12}, "+x"),
                 Reading("P0002", {2500, 1500, 1200}, {0.1 + 0.2, 1.0 / 3.0, 99'999.5}, "-x"),
                 Reading("odd, id", {-0.001, 1e-7, 99'999.0}, {2.2250738585072014e-308, -7.0, 1.0})};
  const auto path = dir / "readings.csv";
  WriteTrackerReadings(path, data);
  const TrackerReadings back = ReadTrackerReadings(path);
  EXPECT_EQ(back.source, path.string());
  EXPECT_FALSE(back.spherical);
  EXPECT_THAT(back.comments, ElementsAre(data.comments[0], data.comments[1]));
  ASSERT_EQ(back.points.size(), data.points.size());
  for (size_t i = 0; i < data.points.size(); ++i) {
    EXPECT_EQ(back.points[i].id, data.points[i].id);
    EXPECT_EQ(back.points[i].approach, data.points[i].approach);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(back.points[i].nominal[k], data.points[i].nominal[k]) << i << " " << k;  // bit for bit
      EXPECT_EQ(back.points[i].measured[k], data.points[i].measured[k]) << i << " " << k;
    }
  }
  EXPECT_EQ(back.points[0].line, 4);  // two comments and the header first
  // Written again, the same bytes.
  const auto again = dir / "again.csv";
  WriteTrackerReadings(again, back);
  EXPECT_EQ(testing::ReadText(again), testing::ReadText(path));
}

// A CMM-measured test piece (fvm testpiece) reads xm,ym,zm as a tracker's Cartesian reading, is written back so,
// and a file naming both sets is refused.
TEST(TrackerReadings, CmmColumnsAreReadWrittenAndNotMixedWithTrackerOnes) {
  testing::TempDir dir;
  const auto path = dir.Write("meas.csv", "id,x,y,z,xm,ym,zm\nT0001,5,5,180,-9.96,23.01,275.03\n");
  const TrackerReadings data = ReadTrackerReadings(path);
  EXPECT_TRUE(data.cmm);
  ASSERT_EQ(data.points.size(), 1u);
  EXPECT_EQ(data.points[0].measured, Eigen::Vector3d(-9.96, 23.01, 275.03));
  const auto again = dir / "again.csv";
  WriteTrackerReadings(again, data);
  EXPECT_THAT(testing::ReadText(again), HasSubstr("id,x,y,z,xm,ym,zm\n"));
  const auto both = dir.Write("both.csv", "id,x,y,z,xm,ym,zm,xt,yt,zt\nA,0,0,0,1,2,3,4,5,6\n");
  EXPECT_THAT(InputErrorOf([&] { ReadTrackerReadings(both); }), HasSubstr("both tracker (xt, yt, zt) and CMM (xm, ym, zm)"));
}

TEST(TrackerReadings, SphericalInputIsConvertedAsComputedByHand) {
  testing::TempDir dir;
  // range 1000 mm, azimuth 30 deg, elevation 45 deg: x = 1000 cos45 cos30 = 612.3724357, y = 1000 cos45 sin30 =
  // 353.5533906, z = 1000 sin45 = 707.1067812.
  const auto path = dir.Write("sph.csv",
                              "# spherical\n"
                              "ID,X,Y,Z,Range,Azimuth,Elevation,temperature\n"
                              "A1,10,20,30,1000,0.5235987755982988,0.7853981633974483,20.1\n"
                              "A2,0,0,0,0,0,0,20.2\n");
  const TrackerReadings r = ReadTrackerReadings(path);
  EXPECT_TRUE(r.spherical);
  ASSERT_EQ(r.points.size(), 2u);
  EXPECT_EQ(r.points[0].nominal, Eigen::Vector3d(10, 20, 30));
  EXPECT_NEAR(r.points[0].measured.x(), 612.3724357, 1e-7);
  EXPECT_NEAR(r.points[0].measured.y(), 353.5533906, 1e-7);
  EXPECT_NEAR(r.points[0].measured.z(), 707.1067812, 1e-7);
  EXPECT_EQ(r.points[1].measured, Eigen::Vector3d::Zero());
  EXPECT_EQ(r.points[0].approach, "");

  // Written spherical and read back: within 1 nm (the conversion costs ~1e-13 relative).
  const auto out = dir / "sph_out.csv";
  WriteTrackerReadings(out, r);
  EXPECT_THAT(testing::ReadText(out), HasSubstr("id,x,y,z,range,azimuth,elevation\n"));
  const TrackerReadings back = ReadTrackerReadings(out);
  EXPECT_TRUE(back.spherical);
  for (size_t i = 0; i < 2; ++i) EXPECT_LT((back.points[i].measured - r.points[i].measured).norm(), 1e-9);
}

TEST(TrackerReadings, ApproachAndExtraColumnsAndSemicolons) {
  testing::TempDir dir;
  const auto path = dir.Write("semi.csv", "id;x;y;z;xt;yt;zt;approach;note\nP1;1;2;3;4;5;6; +x ;a\nP2;1;2;3;4;5;6;;b\n");
  const TrackerReadings r = ReadTrackerReadings(path);
  ASSERT_EQ(r.points.size(), 2u);
  EXPECT_EQ(r.points[0].approach, "+x");
  EXPECT_EQ(r.points[1].approach, "");
  EXPECT_EQ(r.points[1].measured, Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(r.points[1].line, 3);
}

// Every refusal names the file and line, and the point when a row is at fault.
struct BadReadingsCase {
  const char* name;
  const char* text;
  int line;
  const char* point;  // "" for header problems
  const char* says;
};

class TrackerReadingsBadInput : public ::testing::TestWithParam<BadReadingsCase> {};

TEST_P(TrackerReadingsBadInput, NamesFileLineAndPoint) {
  testing::TempDir dir;
  const BadReadingsCase& c = GetParam();
  const auto path = dir.Write("bad.csv", c.text);
  const std::string message = InputErrorOf([&] { ReadTrackerReadings(path); });
  EXPECT_THAT(message, HasSubstr(path.string() + ":" + std::to_string(c.line) + ":"));
  if (*c.point != '\0') {
    EXPECT_THAT(message, HasSubstr(std::string("point ") + c.point));
  }
  EXPECT_THAT(message, HasSubstr(c.says));
}

constexpr const char* kHeader = "id,x,y,z,xt,yt,zt\n";

INSTANTIATE_TEST_SUITE_P(
    All, TrackerReadingsBadInput,
    ::testing::Values(
        BadReadingsCase{"mixed", "# c\nid,x,y,z,xt,yt,zt,range\nP1,0,0,0,1,2,3,4\n", 2, "", "both Cartesian"},
        BadReadingsCase{"neither", "id,x,y,z\nP1,0,0,0\n", 1, "", "no tracker coordinates"},
        BadReadingsCase{"half_a_set", "id,x,y,z,range,azimuth\nP1,0,0,0,1,0\n", 1, "", "'elevation'"},
        BadReadingsCase{"no_z", "id,x,y,xt,yt,zt\nP1,0,0,1,2,3\n", 1, "", "'z'"},
        BadReadingsCase{"no_rows", "# only\nid,x,y,z,xt,yt,zt\n", 2, "", "no point rows"},
        BadReadingsCase{"text", "id,x,y,z,xt,yt,zt\nP1,0,0,0,1,2,3\nP2,0,abc,0,1,2,3\n", 3, "P2", "not a number"},
        BadReadingsCase{"nan", "id,x,y,z,xt,yt,zt\nP1,0,0,0,1,2,3\nP7,0,0,0,nan,2,3\n", 3, "P7", "xt"},
        BadReadingsCase{"inf", "id,x,y,z,xt,yt,zt\nP1,0,0,0,1,2,3\nP8,0,0,0,1,inf,3\n", 3, "P8", "yt"},
        BadReadingsCase{"empty_cell", "id,x,y,z,xt,yt,zt\nP9,0,0,0,1,2,\n", 2, "P9", "zt"},
        BadReadingsCase{"duplicate", "id,x,y,z,xt,yt,zt\nP1,0,0,0,1,2,3\nP2,0,0,0,1,2,3\nP1,1,1,1,1,2,3\n", 4, "P1",
                "first at line 2"},
        BadReadingsCase{"empty_id", "id,x,y,z,xt,yt,zt\n,0,0,0,1,2,3\n", 2, "", "id is empty"},
        BadReadingsCase{"negative_range", "id,x,y,z,range,azimuth,elevation\nP1,0,0,0,1000,0,0\nP2,0,0,0,-5,0,0\n", 3, "P2",
                "negative"},
        BadReadingsCase{"elevation", "id,x,y,z,range,azimuth,elevation\nP3,0,0,0,1000,0,1.5708\n", 2, "P3", "pi/2"},
        BadReadingsCase{"azimuth_degrees", "id,x,y,z,range,azimuth,elevation\nP4,0,0,0,1000,45,0.1\n", 2, "P4", "2 pi"},
        BadReadingsCase{"range_um", "id,x,y,z,range,azimuth,elevation\nP5,0,0,0,1.5e8,0,0\n", 2, "P5", "100 m"},
        BadReadingsCase{"nominal_um", "id,x,y,z,xt,yt,zt\nP6,2500000,0,0,1,2,3\n", 2, "P6", "100 m"},
        BadReadingsCase{"measured_um", "id,x,y,z,xt,yt,zt\nP1,0,0,0,1,2,3\nP6,0,0,0,1,-100001,3\n", 3, "P6", "100 m"},
        BadReadingsCase{"half_a_covariance", "id,x,y,z,xt,yt,zt,cxx,cyy,czz\nP1,0,0,0,1,2,3,1,1,1\n", 1, "",
                "but not cxy,cxz,cyz"},
        BadReadingsCase{"correlation_above_one", "id,x,y,z,xt,yt,zt,cxx,cxy,cxz,cyy,cyz,czz\nP1,0,0,0,1,2,3,1e-4,2e-4,0,1e-4,0,1e-4\n",
                2, "P1", "not positive definite"},
        BadReadingsCase{"negative_variance", "id,x,y,z,xt,yt,zt,cxx,cxy,cxz,cyy,cyz,czz\nP2,0,0,0,1,2,3,-1e-4,0,0,1e-4,0,1e-4\n",
                2, "P2", "not positive definite"}),
    [](const auto& info) { return std::string(info.param.name); });

// A multilaterated point's covariance (mm^2) goes out as cxx..czz and comes back bit for bit, symmetric; a set in
// which some points have one and others not is refused, nothing written.
TEST(TrackerReadings, CovarianceColumnsRoundTripBitExact) {
  testing::TempDir dir;
  TrackerReadings data;
  data.points = {Reading("P1", {0, 0, 0}, {1, 2, 3}), Reading("P2", {10, 0, 0}, {11, 2, 3})};
  Eigen::Matrix3d a;
  a << 1.0 / 3.0, 1e-5, -2e-6, 1e-5, 2.5e-4, 3e-7, -2e-6, 3e-7, 1.0 / 7.0 * 1e-3;
  data.points[0].covariance = a * 1e-3;
  data.points[1].covariance = a;
  const auto path = dir / "ml.csv";
  WriteTrackerReadings(path, data);
  const TrackerReadings back = ReadTrackerReadings(path);
  ASSERT_EQ(back.points.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    ASSERT_TRUE(back.points[i].covariance.has_value());
    EXPECT_EQ(*back.points[i].covariance, *data.points[i].covariance) << "point " << i + 1;
  }
  TrackerReadings some;
  some.points = {Reading("P1", {0, 0, 0}, {1, 2, 3}), Reading("P2", {10, 0, 0}, {11, 2, 3})};
  some.points[1].covariance = a;
  const auto other = dir / "some.csv";
  EXPECT_THAT(InputErrorOf([&] { WriteTrackerReadings(other, some); }), HasSubstr("some points only"));
  EXPECT_FALSE(std::filesystem::exists(other));
}

TEST(TrackerReadings, MissingFileNamesIt) {
  testing::TempDir dir;
  EXPECT_THAT(InputErrorOf([&] { ReadTrackerReadings(dir / "absent.csv"); }), HasSubstr("absent.csv"));
}

TEST(TrackerReadings, WriterRefusesWhatTheReaderWouldAndWritesNothing) {
  testing::TempDir dir;
  const auto path = dir / "out.csv";
  TrackerReadings nan_data;
  nan_data.points = {Reading("P1", {0, 0, 0}, {std::numeric_limits<double>::quiet_NaN(), 0, 0})};
  EXPECT_THAT(InputErrorOf([&] { WriteTrackerReadings(path, nan_data); }), HasSubstr("point P1"));
  TrackerReadings duplicate;
  duplicate.points = {Reading("P1", {0, 0, 0}, {1, 0, 0}), Reading("P1", {1, 0, 0}, {2, 0, 0})};
  EXPECT_THAT(InputErrorOf([&] { WriteTrackerReadings(path, duplicate); }), HasSubstr("twice"));
  TrackerReadings empty;
  EXPECT_THAT(InputErrorOf([&] { WriteTrackerReadings(path, empty); }), HasSubstr("no points"));
  EXPECT_TRUE(dir.Entries().empty());
}

}  // namespace
}  // namespace fvm::artefacts
