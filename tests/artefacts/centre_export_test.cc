#include "artefacts/io/centre_export.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/file_io.h"
#include "core/input_error.h"
#include "tests/support/test_support.h"

namespace fvm::artefacts {
namespace {

using fvm::testing::InputErrorOf;

using ::testing::ElementsAre;
using ::testing::HasSubstr;


CentreRecord Record(int id, double x, double y, double z) {
  CentreRecord r;
  r.id = id;
  r.position = {x, y, z};
  return r;
}

TEST(CentreExport, RoundTripIsExactTo1nm) {
  testing::TempDir dir;
  CentreExport data;
  data.comments = {"Table 1 case a", "second comment"};
  data.centres = {Record(1, -154.54871234, -115.4767, -50.3624), Record(6, -134.5409, -115.43714999, -50.4457),
                  Record(36, 0.0000004, 999.9999994, -0.25)};
  data.centres[0].t_s = 12.5;
  data.centres[1].t_s = 3600.125;
  data.centres[0].radius_mm = 0.2498;
  data.centres[1].form_rms_mm = 0.0001234;
  const auto path = dir / "round.csv";
  WriteCentreExport(path, data);

  const CentreExport back = ReadCentreExport(path);
  EXPECT_EQ(back.source, path.string());
  EXPECT_THAT(back.comments, ElementsAre("Table 1 case a", "second comment"));
  ASSERT_EQ(back.centres.size(), data.centres.size());
  for (size_t i = 0; i < data.centres.size(); ++i) {
    EXPECT_EQ(back.centres[i].id, data.centres[i].id);
    for (int axis = 0; axis < 3; ++axis) {
      EXPECT_NEAR(back.centres[i].position[axis], data.centres[i].position[axis], 1e-6) << "row " << i;
    }
  }
  EXPECT_NEAR(*back.centres[0].t_s, 12.5, 1e-6);
  EXPECT_NEAR(*back.centres[1].t_s, 3600.125, 1e-6);
  EXPECT_FALSE(back.centres[2].t_s.has_value());
  EXPECT_NEAR(*back.centres[0].radius_mm, 0.2498, 1e-6);
  EXPECT_FALSE(back.centres[1].radius_mm.has_value());
  EXPECT_NEAR(*back.centres[1].form_rms_mm, 0.000123, 1e-6);
  EXPECT_EQ(back.centres[0].line, 4);  // two comments and the header come first
  ASSERT_NE(back.Find(6), nullptr);
  EXPECT_EQ(back.Find(6)->line, 5);
  EXPECT_EQ(back.Find(2), nullptr);
}

TEST(CentreExport, WritesSixDecimalsOfMillimetre) {
  testing::TempDir dir;
  CentreExport data;
  data.comments = {"case a"};
  data.centres = {Record(1, -154.5487, -115.4767, -50.3624), Record(6, 1.23456789, 0, 2)};
  data.centres[1].t_s = 4.5;
  const auto path = dir / "six.csv";
  WriteCentreExport(path, data);
  EXPECT_EQ(testing::ReadText(path),
            "# case a\n"
            "id,x,y,z,t\n"
            "1,-154.548700,-115.476700,-50.362400,\n"
            "6,1.234568,0.000000,2.000000,4.500000\n");
}

TEST(CentreExport, HeaderIsCaseInsensitiveTrimmedAndMayUseSemicolonsOrTabs) {
  testing::TempDir dir;
  const auto semicolon = dir.Write("semicolon.csv",
                                   "\xEF\xBB\xBF# exported by a spreadsheet\r\n\r\n"
                                   " ID ; Z ; \"X\" ;Y; Comment\r\n"
                                   "7; -50.5 ; -154.25 ;+115.125; fine\r\n");
  const CentreExport a = ReadCentreExport(semicolon);
  ASSERT_EQ(a.centres.size(), 1u);
  EXPECT_EQ(a.centres[0].id, 7);
  EXPECT_EQ(a.centres[0].position, Eigen::Vector3d(-154.25, 115.125, -50.5));
  EXPECT_THAT(a.comments, ElementsAre("exported by a spreadsheet"));
  EXPECT_EQ(a.centres[0].line, 4);

  const auto tab = dir.Write("tab.csv", "id\tx\ty\tz\tT\n3\t1\t2\t3\t0.5\n");
  const CentreExport b = ReadCentreExport(tab);
  ASSERT_EQ(b.centres.size(), 1u);
  EXPECT_EQ(b.centres[0].position, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(b.centres[0].t_s, 0.5);
}

struct BadCase {
  const char* name;
  const char* content;
  const char* where;  // FILE:LINE the message must name ("" when only the file)
  const char* what;   // the calotte or the problem the message must name
};
// Names the case in test listings (instead of a byte dump that changes from run to run).
void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

class BadCentreExport : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadCentreExport, ThrowsNamingFileLineAndCalotte) {
  testing::TempDir dir;
  const auto path = dir.Write("bad.csv", GetParam().content);
  const std::string message = InputErrorOf([&] { ReadCentreExport(path); });
  EXPECT_THAT(message, HasSubstr(path.string() + GetParam().where));
  EXPECT_THAT(message, HasSubstr(GetParam().what));
  EXPECT_THAT(message, HasSubstr("; "));  // "problem; what to do"
}

INSTANTIATE_TEST_SUITE_P(
    CentreExport, BadCentreExport,
    ::testing::Values(
        BadCase{"HeaderWithoutZ", "# c\nid,x,y\n1,2,3\n", ":2:", "no column 'z'"},
        BadCase{"HeaderMissing", "1,2,3,4\n", ":1:", "add a header line"},
        BadCase{"DuplicateColumn", "id,x,y,z,X\n1,2,3,4,5\n", ":1:", "'x' appears twice"},
        BadCase{"ShortRow", "id,x,y,z\n1,2,3,4\n2,2,3\n", ":3:", "3 fields where the header (line 1) has 4"},
        BadCase{"DecimalComma", "id,x,y,z\n1,2,5,3,4\n", ":2:", "'.' as the decimal mark"},
        BadCase{"NonNumeric", "id,x,y,z\n1,2,3,4\n2,2,abc,4\n", ":3:", "calotte 2: column 'y' (field 3): 'abc' is not a number"},
        BadCase{"EmptyCoordinate", "id,x,y,z\n5,1,,3\n", ":2:", "calotte 5: y is empty"},
        BadCase{"NotAnId", "id,x,y,z\n1.5,1,2,3\n", ":2:", "column 'id' (field 1): '1.5' is not a whole number"},
        BadCase{"NaN", "id,x,y,z\n1,2,3,4\n\n2,nan,3,4\n", ":4:", "calotte 2: x is nan"},
        BadCase{"Infinite", "id,x,y,z,t\n9,1,2,-inf,0\n", ":2:", "calotte 9: z is -inf"},
        BadCase{"NaNTime", "id,x,y,z,t\n9,1,2,3,NaN\n", ":2:", "calotte 9: t is NaN"},
        BadCase{"DuplicateId", "id,x,y,z\n1,2,3,4\n6,2,3,4\n1,2,3,5\n", ":4:", "calotte 1 appears again (first at line 2)"},
        BadCase{"NoRows", "# only a header\nid,x,y,z\n", ":2:", "no calotte rows"},
        BadCase{"Empty", "", ": the file is empty", "no header line"},
        BadCase{"Micrometres", "id,x,y,z\n1,-154548.7,-115476.7,-50362.4\n", ":2:", "calotte 1: x = -154548.7"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.name); });

TEST(CentreExport, MissingFileIsNamed) {
  testing::TempDir dir;
  const auto path = dir / "absent.csv";
  EXPECT_THAT(InputErrorOf([&] { ReadCentreExport(path); }), HasSubstr(path.string() + ": no such file"));
}

TEST(CentreExport, FailingWriteLeavesNoFileBehind) {
  testing::TempDir dir;
  CentreExport data;
  data.centres = {Record(1, 1, 2, 3)};
  // The target is a directory: the rename fails after the content was written to the temporary file.
  std::filesystem::create_directory(dir / "out.csv");
  EXPECT_THAT(InputErrorOf([&] { WriteCentreExport(dir / "out.csv", data); }),
              HasSubstr((dir / "out.csv").string() + ": cannot write"));
  EXPECT_THAT(dir.Entries(), ElementsAre("out.csv"));
  EXPECT_TRUE(std::filesystem::is_directory(dir / "out.csv"));

  // The directory does not exist: nothing can be created.
  EXPECT_THAT(InputErrorOf([&] { WriteCentreExport(dir / "no" / "out.csv", data); }), HasSubstr("no/out.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "no"));

  // A value the reader would refuse: nothing is written at all, an existing file keeps its content.
  const auto keep = dir.Write("keep.csv", "old");
  data.centres[0].position.y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(InputErrorOf([&] { WriteCentreExport(keep, data); }), HasSubstr("calotte 1"));
  EXPECT_EQ(testing::ReadText(keep), "old");
  EXPECT_THAT(dir.Entries(), ElementsAre("keep.csv", "out.csv"));
}

// WriteFileAtomically is what makes every export whole-or-nothing; tested here, where it is used.
TEST(CentreExport, AtomicWriteReplacesContentWholeAndLeavesNoTemporary) {
  testing::TempDir dir;
  const auto path = dir / "a.txt";
  WriteFileAtomically(path, "first version, longer\n");
  WriteFileAtomically(path, "second\n");
  EXPECT_EQ(testing::ReadText(path), "second\n");
  EXPECT_THAT(dir.Entries(), ElementsAre("a.txt"));
  EXPECT_THAT(InputErrorOf([&] { WriteFileAtomically(dir.path() / "", "x"); }), HasSubstr("names a directory"));
  EXPECT_THAT(dir.Entries(), ElementsAre("a.txt"));
}

TEST(CentreExport, AtomicWriteOfNothingIsAnEmptyFile) {
  testing::TempDir dir;
  WriteFileAtomically(dir / "empty", "");
  EXPECT_EQ(std::filesystem::file_size(dir / "empty"), 0u);
  EXPECT_THAT(dir.Entries(), ElementsAre("empty"));
}

}  // namespace
}  // namespace fvm::artefacts
