#include "imaging/io/x3p.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "imaging/height_map.h"
#include "imaging/io/md5.h"
#include "imaging/io/zip_archive.h"
#include "tests/support/test_support.h"
#include "tests/support/surface_samples.h"

namespace fvm::imaging {
namespace {

using fvm::testing::InputErrorOf;
using fvm::testing::TempDir;
using ::testing::AllOf;
using testing::ExpectSameGrid;
using testing::ExpectSameHeights;
using ::testing::HasSubstr;
using testing::SampleMap;

// A main.xml as instruments write it (prefixed root, unqualified records), with Record3's body given.
std::string MainXml(const std::string& cz_type, const std::string& record3,
                    const std::string& size = "3</SizeX><SizeY>2", const std::string& cz_increment = "1",
                    const std::string& cz_offset = "0") {
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2">
  <Record1>
    <Revision>ISO5436 - 2000</Revision>
    <FeatureType>SUR</FeatureType>
    <Axes>
      <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>2e-06</Increment><Offset>0.001</Offset></CX>
      <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>3e-06</Increment><Offset>-0.002</Offset></CY>
      <CZ><AxisType>A</AxisType><DataType>)" +
         cz_type + "</DataType><Increment>" + cz_increment + "</Increment><Offset>" + cz_offset + R"(</Offset></CZ>
    </Axes>
  </Record1>
  <Record2>
    <Date>2024-05-06T07:08:09+02:00</Date>
    <Instrument><Manufacturer>Alicona</Manufacturer><Model>InfiniteFocus G5</Model>
      <Serial>1</Serial><Version>7</Version></Instrument>
    <CalibrationDate>2024-01-01T00:00:00+00:00</CalibrationDate>
    <ProbingSystem><Type>NonContacting</Type><Identification>5x</Identification></ProbingSystem>
  </Record2>
  <Record3>
    <MatrixDimension><SizeX>)" +
         size + R"(</SizeY><SizeZ>1</SizeZ></MatrixDimension>
)" + record3 +
         R"(
  </Record3>
  <Record4><ChecksumFile>md5checksum.hex</ChecksumFile></Record4>
</p:ISO5436_2>
)";
}

std::string ChecksumFile(const std::string& xml) { return Md5Hex(xml) + " *main.xml\n"; }

std::string Container(const std::string& xml, std::vector<ZipEntry> more = {}) {
  std::vector<ZipEntry> entries = {{"main.xml", xml}, {"md5checksum.hex", ChecksumFile(xml)}};
  for (ZipEntry& e : more) entries.push_back(std::move(e));
  return BuildZip(entries);
}

template <typename T>
std::string Binary(const std::vector<T>& values) {
  std::string bytes(values.size() * sizeof(T), '\0');
  std::memcpy(bytes.data(), values.data(), bytes.size());
  return bytes;
}

TEST(X3p, BinaryDoubleRoundTripIsExact) {
  const HeightMap map = SampleMap();
  TempDir dir;
  X3pWriteOptions options;
  options.date = "2024-01-02T03:04:05+00:00";
  WriteX3p(dir / "map.x3p", map, options);
  const HeightMap back = ReadX3p(dir / "map.x3p");
  ExpectSameHeights(map, back);
  ExpectSameGrid(map, back);
  EXPECT_THAT(back.source, HasSubstr("X3P"));
  EXPECT_EQ(dir.Entries(), std::vector<std::string>{"map.x3p"});  // no temporary file left behind
  // Same map, same options: same bytes.
  EXPECT_EQ(BuildX3p(map, options), BuildX3p(map, options));
}

TEST(X3p, InlineDataListRoundTripIsExact) {
  const HeightMap map = SampleMap(4, 3);
  X3pWriteOptions options;
  options.binary = false;
  const HeightMap back = ParseX3p(BuildX3p(map, options), "inline.x3p");
  ExpectSameHeights(map, back);
  ExpectSameGrid(map, back);
}

TEST(X3p, Float32RoundTripKeepsFloatPrecision) {
  const HeightMap map = SampleMap();
  for (const bool binary : {true, false}) {
    X3pWriteOptions options;
    options.z_type = X3pDataType::kFloat32;
    options.binary = binary;
    const HeightMap back = ParseX3p(BuildX3p(map, options), "f.x3p");
    ASSERT_EQ(back.z_mm.size(), map.z_mm.size());
    for (size_t i = 0; i < map.z_mm.size(); ++i) {
      if (std::isnan(map.z_mm[i])) {
        EXPECT_TRUE(std::isnan(back.z_mm[i]));
      } else {
        EXPECT_FLOAT_EQ(back.z_mm[i], map.z_mm[i]) << i;
      }
    }
  }
}

TEST(X3p, IntegerTypesQuantiseToTheIncrement) {
  const HeightMap map = SampleMap();
  for (const X3pDataType type : {X3pDataType::kInt16, X3pDataType::kInt32}) {
    X3pWriteOptions options;
    options.z_type = type;
    options.z_increment_mm = 1e-6;
    const HeightMap back = ParseX3p(BuildX3p(map, options), "i.x3p");
    for (size_t i = 0; i < map.z_mm.size(); ++i) {
      if (std::isnan(map.z_mm[i])) {
        EXPECT_TRUE(std::isnan(back.z_mm[i])) << "invalid points come back through valid.bin";
      } else {
        EXPECT_NEAR(back.z_mm[i], map.z_mm[i], 0.5e-6 + 1e-9) << i;
      }
    }
  }
  X3pWriteOptions no_increment;
  no_increment.z_type = X3pDataType::kInt16;
  EXPECT_THAT(InputErrorOf([&] { BuildX3p(map, no_increment); }), HasSubstr("increment"));
  X3pWriteOptions too_fine;
  too_fine.z_type = X3pDataType::kInt16;
  too_fine.z_increment_mm = 1e-9;  // 12 um in 1 pm steps does not fit 16 bits
  EXPECT_THAT(InputErrorOf([&] { BuildX3p(map, too_fine); }), HasSubstr("beyond the range"));
}

TEST(X3p, AllInvalidMapRoundTrips) {
  HeightMap map = SampleMap(3, 2);
  for (double& z : map.z_mm) z = NAN;
  const HeightMap back = ParseX3p(BuildX3p(map), "nan.x3p");
  EXPECT_EQ(ComputeStats(back).valid_points, 0u);
  ExpectSameHeights(map, back);
}

TEST(X3p, ReadsHandMadeInlineDataList) {
  // Metres in the file, mm in the map; an empty Datum and "NaN" are invalid points.
  const std::string xml = MainXml("D", R"(<DataList>
      <Datum>1.5e-06</Datum><Datum/><Datum>-2.25e-06</Datum>
      <Datum> 0 </Datum><Datum>NaN</Datum><Datum>4e-05</Datum>
    </DataList>)");
  const HeightMap map = ParseX3p(Container(xml), "hand.x3p");
  ASSERT_EQ(map.size_x, 3);
  ASSERT_EQ(map.size_y, 2);
  EXPECT_DOUBLE_EQ(map.dx_mm, 0.002);
  EXPECT_DOUBLE_EQ(map.dy_mm, 0.003);
  EXPECT_DOUBLE_EQ(map.x0_mm, 1.0);
  EXPECT_DOUBLE_EQ(map.y0_mm, -2.0);
  EXPECT_DOUBLE_EQ(map.at(0, 0), 0.0015);
  EXPECT_TRUE(std::isnan(map.at(1, 0)));
  EXPECT_DOUBLE_EQ(map.at(2, 0), -0.00225);
  EXPECT_EQ(map.at(0, 1), 0.0);
  EXPECT_TRUE(std::isnan(map.at(1, 1)));
  EXPECT_DOUBLE_EQ(map.at(2, 1), 0.04);
  EXPECT_THAT(map.source, AllOf(HasSubstr("Alicona InfiniteFocus G5"), HasSubstr("2024-05-06")));
}

// Float64 heights keep float64 precision (issue 17: -808.368571682830 mm came back as -808.3686): read from an
// inline DataList of the OpenGPS samples' form (empty <Datum/> for an invalid point), written as D, read again.
TEST(X3p, Float64HeightsKeepTheirDigits) {
  const std::string xml = MainXml("D", R"(<DataList>
      <Datum>-0.808368571682830</Datum><Datum/><Datum>1.23456789012345e-05</Datum>
      <Datum>0.1</Datum><Datum>-1e-09</Datum><Datum>0.000123456789123</Datum>
    </DataList>)");
  const HeightMap map = ParseX3p(Container(xml), "d.x3p");
  const std::vector<double> expected_mm = {-808.368571682830, NAN, 1.23456789012345e-02, 100.0, -1e-06, 0.123456789123};
  for (size_t i = 0; i < expected_mm.size(); ++i) {
    if (std::isnan(expected_mm[i])) {
      EXPECT_TRUE(std::isnan(map.z_mm[i]));
      continue;
    }
    // Metres to mm is one multiplication by 1000: within an ulp or two of the decimal, 15 significant digits kept.
    EXPECT_DOUBLE_EQ(map.z_mm[i], expected_mm[i]) << i;
    EXPECT_NEAR(map.z_mm[i], expected_mm[i], std::abs(expected_mm[i]) * 1e-15) << i;
  }
  for (const bool binary : {true, false}) {
    X3pWriteOptions options;
    options.binary = binary;
    const HeightMap back = ParseX3p(BuildX3p(map, options), "again.x3p");
    for (size_t i = 0; i < map.z_mm.size(); ++i) {
      if (std::isnan(map.z_mm[i])) continue;
      EXPECT_DOUBLE_EQ(back.z_mm[i], map.z_mm[i]) << i;
    }
  }
}

TEST(X3p, ReadsHandMadeBinaryWithValidityBits) {
  // int16 counts of 0.5 um above an offset of 10 um; point 4 is marked invalid in valid.bin.
  const std::string data = Binary<std::int16_t>({0, 1, -2, 100, 7, -32768});
  const std::string valid(1, static_cast<char>(0b101111));
  const std::string xml = MainXml("I",
                                  R"(<DataLink>
      <PointDataLink>bindata/data.bin</PointDataLink>
      <MD5ChecksumPointData>)" + Md5Hex(data) +
                                      R"(</MD5ChecksumPointData>
      <ValidPointsLink>bindata/valid.bin</ValidPointsLink>
      <MD5ChecksumValidPoints>)" + Md5Hex(valid) +
                                      R"(</MD5ChecksumValidPoints>
    </DataLink>)",
                                  "3</SizeX><SizeY>2", "5e-07", "1e-05");
  const HeightMap map = ParseX3p(Container(xml, {{"bindata/data.bin", data}, {"bindata/valid.bin", valid}}), "b.x3p");
  const std::vector<double> expected_um = {10.0, 10.5, 9.0, 60.0, NAN, 10.0 - 16384.0};
  for (size_t i = 0; i < expected_um.size(); ++i) {
    if (std::isnan(expected_um[i])) {
      EXPECT_TRUE(std::isnan(map.z_mm[i]));
    } else {
      EXPECT_DOUBLE_EQ(map.z_mm[i], expected_um[i] / 1000.0) << i;  // int16 counts scale exactly into double
    }
  }
}

TEST(X3p, ReadsBinaryFloatsWithoutChecksumFile) {
  // Checksums are verified when present; an archive without md5checksum.hex still reads.
  const std::string data = Binary<float>({1e-6f, NAN, 2e-6f, 3e-6f, 4e-6f, 5e-6f});
  const std::string xml = MainXml("F", "<DataLink><PointDataLink>bindata/data.bin</PointDataLink></DataLink>");
  const HeightMap map = ParseX3p(BuildZip({{"main.xml", xml}, {"bindata/data.bin", data}}), "f.x3p");
  EXPECT_FLOAT_EQ(map.z_mm[0], 0.001f);
  EXPECT_TRUE(std::isnan(map.z_mm[1]));
  EXPECT_FLOAT_EQ(map.z_mm[5], 0.005f);
}

TEST(X3p, FindsEntriesStoredWithBackslashes) {
  const std::string data = Binary<double>({1e-6, 2e-6, 3e-6, 4e-6, 5e-6, 6e-6});
  const std::string xml = MainXml("D", "<DataLink><PointDataLink>bindata/data.bin</PointDataLink></DataLink>");
  const HeightMap map = ParseX3p(Container(xml, {{"bindata\\data.bin", data}}), "windows.x3p");
  EXPECT_FLOAT_EQ(map.z_mm[5], 0.006f);
}

TEST(X3p, FailedWriteNamesThePathAndLeavesNothing) {
  TempDir dir;
  EXPECT_THAT(InputErrorOf([&] { WriteX3p(dir / "missing-dir" / "map.x3p", SampleMap()); }),
              AllOf(HasSubstr("missing-dir/map.x3p"), HasSubstr("cannot write")));
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(X3p, WrongDataChecksumNamesFileAndChecksum) {
  const std::string data = Binary<double>({1, 2, 3, 4, 5, 6});
  const std::string xml = MainXml("D", R"(<DataLink><PointDataLink>bindata/data.bin</PointDataLink>
      <MD5ChecksumPointData>0123456789abcdef0123456789abcdef</MD5ChecksumPointData></DataLink>)");
  EXPECT_THAT(InputErrorOf([&] {
                ParseX3p(Container(xml, {{"bindata/data.bin", data}}), "scan.x3p");
              }),
              AllOf(HasSubstr("scan.x3p"), HasSubstr("bindata/data.bin"), HasSubstr("MD5ChecksumPointData"),
                    HasSubstr("0123456789abcdef0123456789abcdef")));
}

TEST(X3p, WrongValidityChecksumIsReported) {
  const std::string data = Binary<double>({1, 2, 3, 4, 5, 6});
  const std::string valid(1, '\x3f');
  const std::string xml = MainXml("D", R"(<DataLink><PointDataLink>bindata/data.bin</PointDataLink>
      <ValidPointsLink>bindata/valid.bin</ValidPointsLink>
      <MD5ChecksumValidPoints>)" + Md5Hex("other") +
                                           R"(</MD5ChecksumValidPoints></DataLink>)");
  EXPECT_THAT(InputErrorOf([&] {
                ParseX3p(Container(xml, {{"bindata/data.bin", data}, {"bindata/valid.bin", valid}}), "v.x3p");
              }),
              AllOf(HasSubstr("bindata/valid.bin"), HasSubstr("MD5ChecksumValidPoints")));
}

TEST(X3p, EditedMainXmlFailsItsChecksum) {
  const std::string xml = MainXml("D",
                                  "<DataList><Datum>1</Datum><Datum>2</Datum><Datum>3</Datum>"
                                  "<Datum>4</Datum><Datum>5</Datum><Datum>6</Datum></DataList>");
  std::string edited = xml;
  edited.replace(edited.find("<Datum>5</Datum>"), 16, "<Datum>9</Datum>");
  const std::string bytes = BuildZip({{"main.xml", edited}, {"md5checksum.hex", ChecksumFile(xml)}});
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(bytes, "edited.x3p"); }),
              AllOf(HasSubstr("edited.x3p"), HasSubstr("main.xml"), HasSubstr("md5checksum.hex")));
  const std::string garbage = BuildZip({{"main.xml", xml}, {"md5checksum.hex", "not a digest"}});
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(garbage, "g.x3p"); }), HasSubstr("not an MD5 digest"));
}

TEST(X3p, TruncatedOrCorruptZipIsAnInputError) {
  const std::string bytes = BuildX3p(SampleMap(40, 30));
  for (const size_t keep : {bytes.size() / 2, bytes.size() - 10, size_t{3}, size_t{0}}) {
    EXPECT_THAT(InputErrorOf([&] { ParseX3p(bytes.substr(0, keep), "cut.x3p"); }), HasSubstr("cut.x3p")) << keep;
  }
  // Damage inside the compressed data: inflate or CRC fails.
  std::string damaged = bytes;
  for (size_t i = 200; i < 260; ++i) damaged[i] = static_cast<char>(damaged[i] ^ 0x5a);
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(damaged, "bad.x3p"); }), HasSubstr("bad.x3p"));
  EXPECT_THAT(InputErrorOf([&] { ParseX3p("just some text, not a zip", "t.x3p"); }), HasSubstr("not a readable zip"));
}

TEST(X3p, XmlThatLiesAboutSizesIsAnInputError) {
  const std::string data = Binary<double>({1, 2, 3, 4, 5, 6});
  const std::string link =
      "<DataLink><PointDataLink>bindata/data.bin</PointDataLink>"
      "<MD5ChecksumPointData>" +
      Md5Hex(data) + "</MD5ChecksumPointData></DataLink>";
  EXPECT_THAT(InputErrorOf([&] {
                ParseX3p(Container(MainXml("D", link, "4</SizeX><SizeY>2"), {{"bindata/data.bin", data}}), "l.x3p");
              }),
              AllOf(HasSubstr("l.x3p"), HasSubstr("4 x 2 = 8 points"), HasSubstr("48 bytes")));
  EXPECT_THAT(InputErrorOf([&] {
                ParseX3p(
                    Container(MainXml("D", link, "2000000000</SizeX><SizeY>2000000000"), {{"bindata/data.bin", data}}),
                    "huge.x3p");
              }),
              HasSubstr("more than fvm can hold"));
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(Container(MainXml("D", link, "-3</SizeX><SizeY>2")), "n.x3p"); }),
              HasSubstr("SizeX"));
  const std::string short_list = "<DataList><Datum>1</Datum><Datum>2</Datum></DataList>";
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(Container(MainXml("D", short_list)), "s.x3p"); }),
              HasSubstr("holds 2 <Datum>"));
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(Container(MainXml("D", link)), "m.x3p"); }),
              HasSubstr("lacks"));  // data.bin linked but absent
}

TEST(X3p, OtherBadContentIsAnInputError) {
  const std::string list =
      "<DataList><Datum>1</Datum><Datum>2</Datum><Datum>3</Datum>"
      "<Datum>4</Datum><Datum>x</Datum><Datum>6</Datum></DataList>";
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(Container(MainXml("D", list)), "x.x3p"); }), HasSubstr("<Datum> 5 is 'x'"));
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(Container(MainXml("Q", list)), "q.x3p"); }), HasSubstr("DataType"));
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(Container("<root/>"), "r.x3p"); }), HasSubstr("not an X3P"));
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(Container("<p:ISO5436_2 xmlns:p='u'><Record1>"), "w.x3p"); }),
              HasSubstr("not well-formed XML"));
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(BuildZip({{"other.txt", "hello"}}), "o.x3p"); }), HasSubstr("no main.xml"));
  std::string cloud = MainXml("D", list);
  cloud.replace(cloud.find("SUR"), 3, "PCL");
  EXPECT_THAT(InputErrorOf([&] { ParseX3p(Container(cloud), "c.x3p"); }), HasSubstr("FeatureType PCL"));
  TempDir dir;
  EXPECT_THAT(InputErrorOf([&] { ReadX3p(dir / "missing.x3p"); }), HasSubstr("no such file"));
  dir.Write("empty.x3p", "");
  EXPECT_THAT(InputErrorOf([&] { ReadX3p(dir / "empty.x3p"); }), AllOf(HasSubstr("empty.x3p"), HasSubstr("empty")));
}

}  // namespace
}  // namespace fvm::imaging
