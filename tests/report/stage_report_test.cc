#include "report/stage_report.h"

#include <gtest/gtest.h>
#include <plplot.h>
#include <unistd.h>  // getpid

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "core/file_io.h"
#include "core/input_error.h"

namespace fvm::report {
namespace {

namespace fs = std::filesystem;

constexpr const char* kPlots[] = {"distance_errors.svg", "error_vectors.svg", "parameters.svg"};

ReportData SampleReport() {
  ReportData data;
  data.title = "fvm calibrate: model 9 on samples/bar17";
  data.summary = {{"model", "9"}, {"placements", "4 identify, 2 validate"}, {"RMS after", "0.41 um"}};
  data.distance_errors_before_um = {-6.5, -3.0, -2.5, 0.5, 1.0, 4.0, 7.5, 12.0};
  data.distance_errors_after_um = {-0.4, -0.1, 0.0, 0.2, 0.3, 0.5};
  // Longest vector 12 um: the scale arrow rounds down to 10 um.
  data.errors_before = {{-180, -20, 12.0, 0.0}, {-100, -100, -3.0, 4.0}, {-20, -180, 0.0, -8.0}};
  data.errors_after = {{-180, -20, 0.3, -0.1}, {-100, -100, 0.1, 0.2}, {-20, -180, -0.2, 0.0}};
  data.parameters = {
      {"xTx1", 1.5, 0.2, "um"}, {"yTy1", -0.8, 0.3, "um"}, {"xWy", 25.0, 4.0, "urad"}, {"yRz0", -12.0, 6.0, "urad"}};
  return data;
}

class WriteReportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Unique per process too: other build trees may run this suite at the same time.
    root_ = fs::temp_directory_path() / ("fvm-report-test-" + std::to_string(getpid()) + "-" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  fs::path root_;
};

TEST_F(WriteReportTest, WritesThePageAndThreeSvgPlotsAndNothingElse) {
  const fs::path dir = root_ / "report";
  WriteReport(dir, SampleReport());
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.insert(entry.path().filename().string());
  EXPECT_EQ(names, (std::set<std::string>{"index.html", kPlots[0], kPlots[1], kPlots[2]}));  // no temporaries
  for (const char* plot : kPlots) {
    const std::string svg = ReadFileBytes(dir / plot);
    EXPECT_TRUE(svg.starts_with("<?xml") || svg.find("<svg") != std::string::npos) << plot;
    EXPECT_NE(svg.find("</svg>"), std::string::npos) << plot << " is not a complete SVG document";
  }
}

TEST_F(WriteReportTest, PageShowsTitleSummaryAndEveryPlotWithoutExternalResources) {
  const ReportData data = SampleReport();
  WriteReport(root_, data);
  const std::string html = ReadFileBytes(root_ / "index.html");
  EXPECT_NE(html.find("<title>" + data.title + "</title>"), std::string::npos);
  EXPECT_NE(html.find("<h1>" + data.title + "</h1>"), std::string::npos);
  for (const auto& [key, value] : data.summary) {
    EXPECT_NE(html.find(">" + key + "<"), std::string::npos) << key;
    EXPECT_NE(html.find(">" + value + "<"), std::string::npos) << value;
  }
  for (const char* plot : kPlots) {
    EXPECT_NE(html.find("<img src=\"" + std::string(plot) + "\""), std::string::npos) << plot;
  }
  EXPECT_EQ(html.find("http"), std::string::npos) << "the page must not fetch anything";
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
}

TEST_F(WriteReportTest, PageEscapesMarkupInTitleAndSummary) {
  ReportData data;
  data.title = "bar <17> & \"grid\"";
  data.summary = {{"a<b", "c&d"}};
  WriteReport(root_, data);
  const std::string html = ReadFileBytes(root_ / "index.html");
  EXPECT_NE(html.find("bar &lt;17&gt; &amp; &quot;grid&quot;"), std::string::npos);
  EXPECT_NE(html.find(">a&lt;b<"), std::string::npos);
  EXPECT_NE(html.find(">c&amp;d<"), std::string::npos);
  EXPECT_EQ(html.find("<17>"), std::string::npos);
}

// Before and after on their own panels and bins: before spans 12 um (30 bins across 24 um round up to 1 um wide),
// after 0.5 um (0.05 um bins); RMS 5.86 and 0.303 um by hand.
TEST_F(WriteReportTest, HistogramsOfKnownDataEachOnTheirOwnBinsWithUnits) {
  WriteReport(root_, SampleReport());
  const std::string svg = ReadFileBytes(root_ / "distance_errors.svg");
  EXPECT_NE(svg.find("distance error (µm)"), std::string::npos);
  EXPECT_NE(svg.find(">count<"), std::string::npos);
  EXPECT_NE(svg.find("Distance errors before compensation"), std::string::npos);
  EXPECT_NE(svg.find("Distance errors after compensation"), std::string::npos);
  EXPECT_NE(svg.find("n = 8, RMS 5.86 µm, max |e| 12 µm; bins 1 µm wide"), std::string::npos);
  EXPECT_NE(svg.find("n = 6, RMS 0.303 µm, max |e| 0.5 µm; bins 0.05 µm wide"), std::string::npos);
}

// Each panel its own magnification: before, 12 um longest over a 200 mm span (x 1000, a 10 um scale arrow); after,
// 0.316 um longest (x 50000, a 0.2 um scale arrow), which at x 1000 would be a third of a millimetre.
TEST_F(WriteReportTest, ErrorVectorPanelsShowStageAxesTravelAndTheirOwnScales) {
  WriteReport(root_, SampleReport());
  const std::string svg = ReadFileBytes(root_ / "error_vectors.svg");
  EXPECT_NE(svg.find("stage x (mm)"), std::string::npos);
  EXPECT_NE(svg.find("stage y (mm)"), std::string::npos);
  EXPECT_NE(svg.find("dashed: stage travel 200 × 200 mm"), std::string::npos);
  EXPECT_NE(svg.find(">10 µm; arrows magnified × 1000<"), std::string::npos) << "before: a round scale arrow";
  EXPECT_NE(svg.find(">0.2 µm; arrows magnified × 50000<"), std::string::npos) << "after: its own scale";
  EXPECT_NE(svg.find("3 positions, longest error 12 µm"), std::string::npos);
  EXPECT_NE(svg.find("3 positions, longest error 0.316 µm"), std::string::npos);
}

TEST_F(WriteReportTest, ParameterPlotHasOnePanelPerUnitAndEveryName) {
  WriteReport(root_, SampleReport());
  const std::string svg = ReadFileBytes(root_ / "parameters.svg");
  EXPECT_NE(svg.find("value (µm)"), std::string::npos);
  EXPECT_NE(svg.find("value (µrad)"), std::string::npos);
  EXPECT_NE(svg.find("Parameters in µrad: value with ± 2u error bars (k = 2)"), std::string::npos);
  for (const auto& p : SampleReport().parameters) EXPECT_NE(svg.find(">" + p.name + "<"), std::string::npos) << p.name;
}

TEST_F(WriteReportTest, EmptyDataStillGivesAReadablePage) {
  ReportData data;
  data.title = "nothing yet";
  ASSERT_NO_THROW(WriteReport(root_, data));
  EXPECT_NE(ReadFileBytes(root_ / "distance_errors.svg").find("no distance errors"), std::string::npos);
  EXPECT_NE(ReadFileBytes(root_ / "error_vectors.svg").find("no lateral errors"), std::string::npos);
  EXPECT_NE(ReadFileBytes(root_ / "parameters.svg").find("no parameters"), std::string::npos);
}

TEST_F(WriteReportTest, SameDataGivesSameBytes) {
  WriteReport(root_ / "a", SampleReport());
  WriteReport(root_ / "b", SampleReport());
  for (const char* name : {"index.html", kPlots[0], kPlots[1], kPlots[2]}) {
    EXPECT_EQ(ReadFileBytes(root_ / "a" / name), ReadFileBytes(root_ / "b" / name)) << name;
  }
}

TEST_F(WriteReportTest, CreatesMissingParentDirectories) {
  const fs::path dir = root_ / "x" / "y" / "report";
  WriteReport(dir, SampleReport());
  EXPECT_TRUE(fs::is_regular_file(dir / "index.html"));
}

TEST_F(WriteReportTest, UnwritableDirThrowsInputErrorNamingItAndLeavesNothing) {
  const fs::path file = root_ / "plain-file";
  std::ofstream(file) << "not a directory\n";
  const fs::path dir = file / "report";
  try {
    WriteReport(dir, SampleReport());
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(dir.string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir));
  EXPECT_EQ(ReadFileBytes(file), "not a directory\n");
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(root_)) names.insert(entry.path().filename().string());
  EXPECT_EQ(names, std::set<std::string>{"plain-file"});
}

TEST_F(WriteReportTest, DirThatIsAFileThrowsInputError) {
  const fs::path file = root_ / "report";
  std::ofstream(file) << "x";
  EXPECT_THROW(WriteReport(file, SampleReport()), InputError);
  EXPECT_EQ(ReadFileBytes(file), "x");
}

TEST_F(WriteReportTest, KeepsTheCallersPlplotStreamCurrentAndUsable) {
  PLINT mine = -1;
  plmkstrm(&mine);
  ASSERT_GE(mine, 0);
  plsdev("svg");
  plsfnam((root_ / "mine.svg").c_str());
  plinit();
  plenv(0, 1, 0, 1, 0, 0);
  WriteReport(root_ / "report", SampleReport());
  PLINT current = -1;
  plgstrm(&current);
  EXPECT_EQ(current, mine);
  pllab("x", "y", "Mine");
  plend1();
  const std::string svg = ReadFileBytes(root_ / "mine.svg");
  EXPECT_NE(svg.find("&#x4d;&#x69;&#x6e;&#x65;"), std::string::npos) << "the caller's title went to its own file";
}

}  // namespace
}  // namespace fvm::report
