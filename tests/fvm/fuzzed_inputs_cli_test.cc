// The five faults black-box fuzzing of the executable found (issue 44), each input generated here as the fuzzer
// made it: every one now ends with a clear error naming the file (exit 1, nothing written) or a correct result.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "imaging/focus_stack.h"
#include "imaging/io/focus_stack_io.h"
#include "tests/fvm/mutation_support.h"
#include "tests/support/run_fvm.h"
#include "tests/support/test_support.h"

namespace fvm::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

// Rewrites cell `column` of the data rows of a CSV (after '#' lines and the header) for which `row` says so.
void SetCells(const fs::path& file, size_t column, const std::string& value, const std::function<bool(int line)>& row) {
  std::vector<std::string> lines = Lines(ReadText(file));
  bool header = true;
  for (size_t k = 0; k < lines.size(); ++k) {
    if (lines[k].empty() || lines[k][0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    if (!row(static_cast<int>(k) + 1)) continue;
    std::vector<std::string> cells = Cells(lines[k]);
    cells.at(column) = value;
    lines[k] = Join(cells, ",");
  }
  std::ofstream(file, std::ios::trunc) << Join(lines, "\n") + "\n";
}

class FuzzedInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(RunFvm(dir_, "simulate fvm-batch -o " + Path("batch") + " --seed 1").status, 0);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  TempDir dir_;
};

// Every stitching-free x of one placement 1e-310 (a subnormal number): diagnose died with SIGSEGV in the scoring's
// pivoting QR. The reader refuses the number, naming file, line and column.
TEST_F(FuzzedInputs, SubnormalCoordinatesAreRefusedWhereTheyAreRead) {
  SetCells(dir_ / "batch/id-y.free.csv", 1, "1e-310", [](int) { return true; });
  const FvmRun run = RunFvm(dir_, "diagnose " + Path("batch") + " --model 27");
  EXPECT_EQ(run.status, 1) << run.err;
  EXPECT_THAT(run.err, HasSubstr("id-y.free.csv:3: calotte 1: column 'x' (field 2): '1e-310' is a subnormal number"));
}

// The inputs that cannot carry a stage error are refused where they are read: a placement collapsed to one point.
TEST_F(FuzzedInputs, ACollapsedPlacementIsRefusedWithItsFile) {
  SetCells(dir_ / "batch/id-x.free.csv", 1, "-100.0", [](int) { return true; });
  SetCells(dir_ / "batch/id-x.free.csv", 2, "-15.0", [](int) { return true; });
  const FvmRun run = RunFvm(dir_, "calibrate " + Path("batch") + " --model 15 -o " + Path("cal.json"));
  EXPECT_EQ(run.status, 1) << run.err;
  EXPECT_THAT(run.err, HasSubstr("id-x.free.csv: its 17 calottes span 0 um in x and 0 um in y, less than 10 um"));
  EXPECT_FALSE(fs::exists(dir_ / "cal.json"));
}

// One stitched y of -1 instead of about -135 (line 15 of id-y.stitched.csv, calotte 13): diagnose died with
// SIGSEGV. A gross outlier is what the outliers candidate is for: it is named, and the rest diagnosed without it.
TEST_F(FuzzedInputs, OneGrossOutlierIsDiagnosedAsTheOutlier) {
  SetCells(dir_ / "batch/id-y.stitched.csv", 2, "-1", [](int line) { return line == 15; });
  const FvmRun run = RunFvm(dir_, "diagnose " + Path("batch") + " --model 15 --json");
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr("\"effect\": \"outliers\""));
  EXPECT_THAT(run.out, HasSubstr("id-y"));
  EXPECT_FALSE(HoldsNonFinite(run.out)) << run.out;
}

// batch.json holding a million nested arrays: calibrate died of a stack overflow in the JSON parser. Refused before
// parsing, with file and line.
TEST_F(FuzzedInputs, DeepJsonIsRefusedWithFileAndLine) {
  const int n = 1000000;
  std::ofstream(dir_ / "batch/batch.json", std::ios::trunc)
      << "{\"identify\": [\"id-x\", \"id-y\", \"id-oblique\"], \"validate\": [\"val-01\", \"val-02\"], \"lens\": "
      << std::string(n, '[') << std::string(n, ']') << "}\n";
  const FvmRun run = RunFvm(dir_, "calibrate " + Path("batch") + " --model 27 -o " + Path("cal.json"));
  EXPECT_EQ(run.status, 1) << run.err;
  EXPECT_THAT(run.err, HasSubstr("batch.json:1: arrays and objects nested deeper than 64 levels"));
  EXPECT_FALSE(fs::exists(dir_ / "cal.json"));
}

// An empty optional t on one row of a centre export with its columns reordered: correct wrote 'nan' into t. The
// empty field is passed through empty; every other value is written as read.
TEST_F(FuzzedInputs, AnEmptyOptionalFieldIsPassedThroughEmpty) {
  ASSERT_EQ(RunFvm(dir_, "calibrate " + Path("batch") + " --model 27 -o " + Path("cal.json")).status, 0);
  // x,id,y,z,t as the fuzzer reordered them, t of calotte 14 (line 16) empty.
  std::vector<std::string> lines = Lines(ReadText(dir_ / "batch/val-01.free.csv"));
  std::string in;
  int line = 0;
  for (const std::string& l : lines) {
    ++line;
    if (l.empty() || l[0] == '#') {
      in += l + "\n";
      continue;
    }
    std::vector<std::string> c = Cells(l);
    if (line == 16) c[4].clear();
    in += Join({c[1], c[0], c[2], c[3], c[4]}, ",") + "\n";
  }
  std::ofstream(dir_ / "in.csv") << in;
  const FvmRun run = RunFvm(dir_, "correct --calibration " + Path("cal.json") + " " + Path("in.csv") + " -o " + Path("out.csv"));
  ASSERT_EQ(run.status, 0) << run.err;
  const std::string out = ReadText(dir_ / "out.csv");
  EXPECT_FALSE(HoldsNonFinite(out)) << out;
  int rows = 0, empty_t = 0;
  for (const std::string& l : Lines(out)) {
    if (l.empty() || l[0] == '#' || l.starts_with("id,")) continue;
    ++rows;
    const std::vector<std::string> c = Cells(l + ",");  // a trailing empty field kept
    if (c.size() == 8 && c[7].empty()) ++empty_t;
    if (c[0] == "14") {
      EXPECT_EQ(c.size(), 8u) << l;
    }
  }
  EXPECT_EQ(rows, 17);
  EXPECT_EQ(empty_t, 1);
}

// Writes a focus stack of 9 textured 48 x 48 px images; image `bad` (if any) float, every pixel -3.4e38.
fs::path WriteStack(const TempDir& dir, int bad) {
  std::mt19937 random(7);
  std::string csv = "file,z_mm\n";
  std::vector<std::uint8_t> texture(48 * 48);
  for (std::uint8_t& p : texture) p = static_cast<std::uint8_t>(random() % 256);
  for (int k = 0; k < 9; ++k) {
    imaging::StackImage image;
    image.width = image.height = 48;
    if (k == bad) {
      image.pixels = std::vector<float>(48 * 48, -std::numeric_limits<float>::max());
    } else {
      // Sharpest at slice 4: the texture's contrast falls with the distance from it.
      std::vector<std::uint8_t> pixels(texture.size());
      const double contrast = 1.0 / (1.0 + 0.5 * (k - 4) * (k - 4));
      for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<std::uint8_t>(128 + contrast * (texture[i] - 128.0));
      image.pixels = std::move(pixels);
    }
    const std::string name = "img0" + std::to_string(k) + ".tif";
    imaging::WriteStackImage(dir / name, image);
    csv += name + "," + std::to_string(0.001 * k) + "\n";
  }
  return dir.Write("stack.csv", csv);
}

// One image of the stack all -3.4e38: focus exited 0 with no valid point and printed "median quality -nan". The
// image is refused, named; nothing is written.
TEST_F(FuzzedInputs, FocusRefusesAnAbsurdImageAndWritesNothing) {
  const fs::path stack = WriteStack(dir_, 2);
  const FvmRun run = RunFvm(dir_, "focus " + stack.string() + " -o " + Path("h.x3p"));
  EXPECT_EQ(run.status, 1) << run.err;
  EXPECT_THAT(run.err, HasSubstr("img02.tif"));
  EXPECT_THAT(run.err, HasSubstr("has the brightness -3.4"));
  EXPECT_FALSE(fs::exists(dir_ / "h.x3p"));
}

// A stack no pixel of which has a focus peak (every image the same): exit 1 with the reason, nothing written. The
// same stack with its focus (the control) gives heights.
TEST_F(FuzzedInputs, FocusWithNoValidPointExitsOneWithTheReason) {
  const fs::path stack = WriteStack(dir_, -1);
  const FvmRun good = RunFvm(dir_, "focus " + stack.string() + " -o " + Path("good.x3p") + " --json");
  ASSERT_EQ(good.status, 0) << good.err;
  EXPECT_THAT(good.out, Not(HasSubstr("\"valid_points\": 0,")));
  imaging::StackImage flat;
  flat.width = flat.height = 48;
  flat.pixels = std::vector<std::uint8_t>(48 * 48, 128);
  for (int k = 0; k < 9; ++k) imaging::WriteStackImage(dir_ / ("img0" + std::to_string(k) + ".tif"), flat);
  const FvmRun run = RunFvm(dir_, "focus " + stack.string() + " -o " + Path("h.x3p") + " --json");
  EXPECT_EQ(run.status, 1) << run.err;
  EXPECT_THAT(run.err, HasSubstr("stack.csv: no pixel of the 9 images has a focus peak"));
  EXPECT_FALSE(fs::exists(dir_ / "h.x3p"));
  EXPECT_TRUE(run.out.empty()) << run.out;
}

}  // namespace
}  // namespace fvm::testing
