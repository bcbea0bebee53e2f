// The report of `fvm verify --report`: the page and its three plots, the tables on the page, and a directory it
// cannot write refused with nothing left behind.

#include "report/machine_report.h"

#include <gtest/gtest.h>
#include <unistd.h>  // getpid

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "core/file_io.h"
#include "core/input_error.h"

namespace fvm::report {
namespace {

namespace fs = std::filesystem;

MachineReportData SampleMachineReport() {
  MachineReportData data;
  data.title = "fvm verify: XFYZ order 2 <test>";
  data.summary = {{"points", "4"}};
  for (int k = 0; k < 3; ++k) {
    MachineReportData::AxisFunctions& f = data.functions[static_cast<size_t>(k)];
    f.axis = std::string(1, "XYZ"[k]);
    for (int i = 0; i <= 10; ++i) f.position_mm.push_back(100.0 * i);
    for (const char* kind : {"Tx", "Ty", "Tz"}) {
      MachineReportData::Curve c{std::string(1, "xyz"[k]) + kind, {}, {}};
      for (int i = 0; i <= 10; ++i) c.value.push_back(std::sin(0.3 * i + k)), c.u.push_back(0.05 * i);
      f.translations.push_back(c);
      c.name[1] = 'R';
      f.rotations.push_back(c);
    }
  }
  data.readings = {{0, 0, 0, 10, 1}, {500, 0, 0, 20, 2}, {0, 400, 300, 30, 1.5}, {1000, 400, 600, 40, 3}};
  data.validation = {{250, 200, 150, 15, 2.5}};
  data.tables.push_back({"Terms the data cannot separate", "", {"coefficient", "reason"}, {{"xTx0", "same effect as 1 * pose_tx"}}});
  return data;
}

class WriteMachineReportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("fvm-machine-report-test-" + std::to_string(getpid()) + "-" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
};

TEST_F(WriteMachineReportTest, WritesThePageAndThreePlots) {
  WriteMachineReport(root_ / "r", SampleMachineReport());
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(root_ / "r")) names.insert(entry.path().filename().string());
  EXPECT_EQ(names, (std::set<std::string>{"index.html", "error_functions.svg", "volumetric_errors.svg", "error_map.svg"}));
  const std::string page = ReadFileBytes(root_ / "r" / "index.html");
  EXPECT_NE(page.find("XFYZ order 2 &lt;test&gt;"), std::string::npos);
  EXPECT_NE(page.find("<th scope=\"col\">coefficient</th>"), std::string::npos);
  EXPECT_NE(page.find("<td>same effect as 1 * pose_tx</td>"), std::string::npos);
  const std::string functions = ReadFileBytes(root_ / "r" / "error_functions.svg");
  for (const char* label : {"xTx", "yRy", "zTz", "X translations", "Z rotations"}) {
    EXPECT_NE(functions.find(label), std::string::npos) << label;
  }
  EXPECT_NE(ReadFileBytes(root_ / "r" / "volumetric_errors.svg").find("validation, after: n = 1"), std::string::npos);
  for (const char* label : {"X position (mm)", ">error (µm)<", ">error (µrad)<"}) {
    EXPECT_NE(functions.find(label), std::string::npos) << label;
  }
  // Before and after side by side, each with its own disc scale under its heading.
  const std::string map = ReadFileBytes(root_ / "r" / "error_map.svg");
  for (const char* label : {"XZ view, from the front", "XY view, from above", "Before: the ideal machine",
                            "After: the identified model"}) {
    EXPECT_NE(map.find(label), std::string::npos) << label;
  }
  const std::size_t first_scale = map.find("mm per µm");
  ASSERT_NE(first_scale, std::string::npos);
  EXPECT_NE(map.find("mm per µm", first_scale + 1), std::string::npos) << "each side states its disc scale";
}

TEST_F(WriteMachineReportTest, RefusesADirectoryItCannotWriteAndLeavesNothing) {
  std::ofstream(root_ / "file") << "x";
  EXPECT_THROW(WriteMachineReport(root_ / "file" / "r", SampleMachineReport()), InputError);
  EXPECT_EQ(std::distance(fs::directory_iterator(root_), fs::directory_iterator()), 1);
}

}  // namespace
}  // namespace fvm::report
