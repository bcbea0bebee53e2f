// The one CSV layer: the dialect (quotes parsed before splitting, ';' and tab, comments, CRLF, BOM), numbers that
// do not depend on the locale, the exact wording of its errors, its bounds, and the writer's round trip.

#include "core/csv.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <clocale>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

std::string ErrorOf(const std::function<void()>& run) {
  try {
    run();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

std::string ParseError(std::string_view text, const CsvOptions& options = {}) {
  return ErrorOf([&] { ParseCsv(text, "f.csv", options); });
}

TEST(Csv, QuotedFieldsHoldSeparatorsDoubledQuotesAndLineBreaks) {
  const CsvTable table = ParseCsv(
      "name,x,note\n"
      "\"a,b\",1.5,\"say \"\"hi\"\"\"\n"
      " \"multi\nline\" ,2,plain\n"
      "last,3,\"  kept  \"\n",
      "f.csv");
  EXPECT_EQ(table.separator(), ',');
  ASSERT_EQ(table.rows().size(), 3u);
  EXPECT_THAT(table.rows()[0].fields, ElementsAre("a,b", "1.5", "say \"hi\""));
  EXPECT_THAT(table.rows()[1].fields, ElementsAre("multi\nline", "2", "plain"));
  EXPECT_THAT(table.rows()[2].fields, ElementsAre("last", "3", "  kept  "));  // blanks inside quotes are data
  // A row is numbered by the line it starts on; the quoted line break moves the next row down one line.
  EXPECT_EQ(table.rows()[1].line, 3);
  EXPECT_EQ(table.rows()[2].line, 5);
  EXPECT_EQ(table.Double(table.rows()[0], table.Require("X")), 1.5);
}

TEST(Csv, SemicolonAndTabAreTakenFromTheHeader) {
  const CsvTable semicolon = ParseCsv(" ID ; X ;\"a;b\"\n 7 ; -2.5 ;\"1,5\"\n", "s.csv");
  EXPECT_EQ(semicolon.separator(), ';');
  EXPECT_THAT(semicolon.header(), ElementsAre("ID", "X", "a;b"));
  EXPECT_EQ(semicolon.Int(semicolon.rows()[0], semicolon.Require("id"), 0, 10), 7);
  EXPECT_EQ(semicolon.Double(semicolon.rows()[0], semicolon.Require("x")), -2.5);
  EXPECT_EQ(semicolon.Text(semicolon.rows()[0], semicolon.Require("A;B")), "1,5");

  const CsvTable tab = ParseCsv("id\tx\tname\n3\t 0.25\tone, two\n", "t.csv");
  EXPECT_EQ(tab.separator(), '\t');
  EXPECT_THAT(tab.rows()[0].fields, ElementsAre("3", "0.25", "one, two"));

  CsvOptions given;
  given.separator = ';';  // a comma-rich header does not override a separator the caller knows
  EXPECT_THAT(ParseCsv("a,b,c;d\n1,2;3\n", "g.csv", given).rows()[0].fields, ElementsAre("1,2", "3"));
}

TEST(Csv, CommentAndBlankLinesAreSkippedAndCounted) {
  const CsvTable table = ParseCsv("# first\n\n   # second, with a comma\nid,x\n#between\n\n1,2\n", "c.csv");
  EXPECT_THAT(table.comments(), ElementsAre("first", "second, with a comma", "between"));
  EXPECT_EQ(table.header_line(), 4);
  ASSERT_EQ(table.rows().size(), 1u);
  EXPECT_EQ(table.rows()[0].line, 7);
  // A field that starts with '#' is data when quoted, which is how CsvField writes it.
  EXPECT_THAT(ParseCsv("file\n\"#1.tif\"\n", "h.csv").rows()[0].fields, ElementsAre("#1.tif"));
}

TEST(Csv, CrLfAndByteOrderMarkAreInvisible) {
  const CsvTable table = ParseCsv("\xEF\xBB\xBFid,x\r\n1,2\r\n\r\n3,\"4\"\r\n5,\r\n", "w.csv");
  EXPECT_THAT(table.header(), ElementsAre("id", "x"));
  ASSERT_EQ(table.rows().size(), 3u);
  EXPECT_THAT(table.rows()[0].fields, ElementsAre("1", "2"));
  EXPECT_THAT(table.rows()[1].fields, ElementsAre("3", "4"));
  EXPECT_EQ(table.rows()[1].line, 4);
  EXPECT_EQ(table.OptionalDouble(table.rows()[2], 1), std::nullopt);  // "5," : an empty last cell, no '\r'
}

// Numbers are read and written with '.' whatever the C locale says. The test needs a locale with a decimal comma;
// it proves the locale is active (strtod reads "1.5" as 1) before asserting that ours did not change.
TEST(Csv, GermanLocaleDoesNotChangeNumbers) {
  const std::string before = std::setlocale(LC_ALL, nullptr);
  const char* german = nullptr;
  for (const char* name : {"de_DE.UTF-8", "de_DE.utf8", "de_DE"}) {
    if (std::setlocale(LC_ALL, name) != nullptr) {
      german = name;
      break;
    }
  }
  if (german == nullptr) GTEST_SKIP() << "no German locale installed (locale -a); numbers not checked under one";
  ASSERT_EQ(std::strtod("1.5", nullptr), 1.0) << german << " does not use a decimal comma";
  const CsvTable table = ParseCsv("x;y\n1.5;-0.125e-3\n", "de.csv");
  EXPECT_EQ(table.Double(table.rows()[0], 0), 1.5);
  EXPECT_EQ(table.Double(table.rows()[0], 1), -0.125e-3);
  EXPECT_EQ(FormatShortest(0.1), "0.1");
  EXPECT_EQ(FormatFixed(-154.5487, 6), "-154.548700");
  std::setlocale(LC_ALL, before.c_str());
}

TEST(Csv, NumbersAreWholeFieldsAndFixedFormatMatchesPrintf) {
  const CsvTable table = ParseCsv("x,n\n+2.5e1,+12\n", "n.csv");
  EXPECT_EQ(table.Double(table.rows()[0], 0), 25.0);
  EXPECT_EQ(table.Int(table.rows()[0], 1, 0, 12), 12);
  EXPECT_EQ(FormatFixed(1.0 / 3.0, 6), "0.333333");
  EXPECT_EQ(FormatFixed(-0.0000004, 6), "-0.000000");  // as printf("%.6f") writes it
  EXPECT_EQ(FormatFixed(2.5, 0), "2");                 // round half to even, as printf
  EXPECT_EQ(AsciiLower("Form_RMS"), "form_rms");
}

// The wording every reader shares: "FILE:LINE: [context: ]column 'name' (field N): problem; what to do".
TEST(Csv, CellErrorsNameFileLineAndColumnExactly) {
  const CsvTable table = ParseCsv("id,x,Y,col\n1,2,abc,2147483647\n2,,nan,1.5\n", "f.csv");
  const CsvRow& first = table.rows()[0];
  const CsvRow& second = table.rows()[1];
  EXPECT_EQ(ErrorOf([&] { table.Double(first, table.Require("y")); }),
            "f.csv:2: column 'Y' (field 3): 'abc' is not a number; write plain numbers with '.' as the decimal mark");
  EXPECT_EQ(ErrorOf([&] { table.Double(first, table.Require("y"), "calotte 1"); }),
            "f.csv:2: calotte 1: column 'Y' (field 3): 'abc' is not a number; write plain numbers with '.' as the "
            "decimal mark");
  EXPECT_EQ(ErrorOf([&] { table.Int(first, table.Require("col"), 0, 99999); }),
            "f.csv:2: column 'col' (field 4): 2147483647 is out of range; give a whole number from 0 to 99999");
  EXPECT_EQ(ErrorOf([&] { table.Int(second, table.Require("col"), 0, 99999); }),
            "f.csv:3: column 'col' (field 4): '1.5' is not a whole number; give a whole number from 0 to 99999");
  EXPECT_EQ(ErrorOf([&] { table.Double(second, table.Require("x")); }),
            "f.csv:3: column 'x' (field 2) is empty; every row needs a number here");
  EXPECT_EQ(ErrorOf([&] { table.Double(second, table.Require("y")); }),
            "f.csv:3: column 'Y' (field 3) is nan; give a finite number");
  EXPECT_TRUE(std::isnan(*table.OptionalDouble(second, table.Require("y"))));  // the caller decides what nan means
  EXPECT_EQ(ErrorOf([&] { table.Fail(second, "tile 2 is absent; check the path"); }),
            "f.csv:3: tile 2 is absent; check the path");
}

TEST(Csv, TableErrorsNameFileAndLineExactly) {
  CsvOptions centres;
  centres.expected_header = "id,x,y,z";
  EXPECT_EQ(ErrorOf([&] { ParseCsv("# c\nid,x,y\n1,2,3\n", "f.csv", centres).Require("z"); }),
            "f.csv:2: the header has no column 'z'; the first line that is not a '#' comment names the columns "
            "id,x,y,z");
  EXPECT_EQ(ErrorOf([&] { ParseCsv("1,2,3,4\n", "f.csv", centres).Require("id"); }),
            "f.csv:1: the header has no column 'id'; this line looks like data: add a header line id,x,y,z above "
            "the rows");
  EXPECT_EQ(ParseError("id,x,y\n1,2,3\n4,5\n"),
            "f.csv:3: 2 fields where the header (line 1) has 3; give every row one value per header column, "
            "separated by ','");
  EXPECT_EQ(ParseError("id;x\n1;2;3\n"),
            "f.csv:2: 3 fields where the header (line 1) has 2; give every row one value per header column, "
            "separated by ';'");
  EXPECT_EQ(ParseError("id,x\n1,2,5\n"),
            "f.csv:2: 3 fields where the header (line 1) has 2; write numbers with '.' as the decimal mark, not ','");
  EXPECT_EQ(ParseError("id,X,x\n"),
            "f.csv:1: column 'x' appears twice in the header (fields 2 and 3); keep one of them");
  EXPECT_EQ(ParseError("a,b\n1,\"open\n2,3\n"),
            "f.csv:2: field 2: the quote opened here is never closed; close the field with \" (a quote inside a "
            "quoted field is written \"\")");
  EXPECT_EQ(ParseError("a,b\n\"x\"y,1\n"),
            "f.csv:2: field 1: text after the closing quote; quote the whole field and write a quote inside it as "
            "\"\"");
  EXPECT_EQ(ErrorOf([&] { ParseCsv("", "f.csv", centres); }),
            "f.csv: the file is empty, no header line; write a header line id,x,y,z and the rows below it");
  EXPECT_EQ(ErrorOf([&] { ParseCsv("# a\n\n", "f.csv", centres); }),
            "f.csv:2: no header line (only comments or blank lines); the first line that is not a '#' comment must "
            "name the columns (id,x,y,z)");
}

TEST(Csv, BoundsAreCheckedBeforeTheTableGrows) {
  CsvOptions small;
  small.max_rows = 2;
  small.max_columns = 3;
  EXPECT_EQ(ParseError("a\n1\n2\n# c\n3\n", small),
            "f.csv:5: more than 2 rows; split the table or check that this is the right file");
  EXPECT_EQ(ParseError("a,b,c,d\n", small),
            "f.csv:1: more than 3 fields in one row; is this a CSV table? (separator ',')");
  EXPECT_NO_THROW(ParseCsv("a,b,c\n1,2,3\n4,5,6\n", "f.csv", small));
  small.max_bytes = 8;
  EXPECT_EQ(ParseError("a,b,c\n1,2,3\n", small),
            "f.csv: 12 bytes is more than the 8 a CSV table may have here; is this the right file?");
}

TEST(Csv, ReadsFilesAndNamesThemInMessages) {
  const auto dir = std::filesystem::temp_directory_path() / ("fvm_csv_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / "table.csv";
  std::ofstream(path, std::ios::binary) << "id,x\n1,abc\n";
  const CsvTable table = ReadCsv(path);
  EXPECT_EQ(table.name(), path.string());
  EXPECT_THAT(ErrorOf([&] { table.Double(table.rows()[0], 1); }), HasSubstr(path.string() + ":2: column 'x'"));
  EXPECT_THAT(ErrorOf([&] { ReadCsv(dir / "absent.csv"); }), HasSubstr((dir / "absent.csv").string() + ": "));
  std::filesystem::remove_all(dir);
}

TEST(Csv, WrittenFieldsReadBackUnchanged) {
  EXPECT_EQ(CsvField("tile_r000_c001.tif"), "tile_r000_c001.tif");
  EXPECT_EQ(CsvField("a,b"), "\"a,b\"");
  EXPECT_EQ(CsvField("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(CsvField("#1"), "\"#1\"");
  const std::vector<std::string> header = {"file", "note", "x"};
  const std::vector<std::vector<std::string>> rows = {
      {"a,b.tif", "say \"hi\"", "1.5"}, {"#hash", "multi\nline", ""}, {" padded ", "semi;colon\ttab", "-2"}};
  for (const char separator : {',', ';', '\t'}) {
    std::string text = CsvLine(header, separator);
    for (const auto& row : rows) text += CsvLine(row, separator);
    const CsvTable table = ParseCsv(text, "round.csv");
    EXPECT_EQ(table.separator(), separator);
    EXPECT_EQ(table.header(), header);
    ASSERT_EQ(table.rows().size(), rows.size());
    for (std::size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(table.rows()[i].fields, rows[i]) << "row " << i;
  }
}

// A subnormal number is no measurement (issue 44: stitching-free x of 1e-310 crashed fvm diagnose further on): refused
// with file, line and column wherever a CSV cell is read; 0 and the smallest normal number are numbers.
TEST(Csv, SubnormalNumbersAreRefusedWithFileLineAndColumn) {
  const CsvTable table = ParseCsv("id,x\n1,1e-310\n2,0\n3,2.3e-308\n4,-4.9e-324\n", "n.csv");
  EXPECT_THAT(ErrorOf([&] { table.OptionalDouble(table.rows()[0], 1); }),
              HasSubstr("n.csv:2: column 'x' (field 2): '1e-310' is a subnormal number"));
  EXPECT_EQ(table.Double(table.rows()[1], 1), 0.0);
  EXPECT_EQ(table.Double(table.rows()[2], 1), 2.3e-308);
  EXPECT_THAT(ErrorOf([&] { table.Double(table.rows()[3], 1); }), HasSubstr("n.csv:5: column 'x'"));
}

}  // namespace
}  // namespace fvm
