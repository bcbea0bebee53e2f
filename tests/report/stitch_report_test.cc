// The report of `fvm stitch --report DIR` (issue 43): from a stitched layout's summary, the page shows the numbers
// --json and the positions CSV hold (to the digits the page prints), every pair with its status, the loops'
// misclosures, and with --distortion the field's terms with u, its plot and the overlap NCC before and after.

#include <fmt/core.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "report/report.h"
#include "tests/support/test_support.h"
#include "workflows/stitch_layout.h"
#include "workflows/stitch_summary.h"
#include "workflows/tiles_synthesize.h"

namespace fvm::workflows {
namespace {

std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// 3 x 3 tiles of 256 px with a stage error of 1.5 px, stitched with and without a field, the report written.
struct StitchedSet {
  fvm::testing::TempDir dir;
  StitchedLayout stitched;
  Summary summary;
  std::string page;
};

void StitchAndReport(StitchedSet& set, bool distortion) {
  TilesSynthesizeOptions synthesize;
  synthesize.output = (set.dir.path() / "tiles").string();
  synthesize.rows = 3, synthesize.cols = 3, synthesize.bits = 8, synthesize.seed = 4;
  SynthesizeTileSet(synthesize);
  const LayoutTiles tiles = ReadLayoutTiles(set.dir.path() / "tiles" / "layout.csv");
  StitchLayoutOptions options;
  options.stitch.overlap = 0.2;
  options.stitch.pixel_mm = 0.001;
  if (distortion) options.distortion = StitchDistortionOptions{};
  set.stitched = StitchLayout(tiles.layout, tiles.images, options);
  set.summary = Summarize(set.stitched);
  ASSERT_TRUE(set.summary.report.has_value());
  report::Write(set.dir.path() / "report", *set.summary.report);
  set.page = ReadText(set.dir.path() / "report" / "index.html");
}

bool Shows(const std::string& page, const std::string& cell) { return page.find("<td>" + cell + "</td>") != std::string::npos; }

TEST(StitchReport, ShowsTheTilesPairsAndLoopsAsJsonHasThem) {
  StitchedSet set;
  StitchAndReport(set, false);
  const nlohmann::ordered_json& json = set.summary.json;
  EXPECT_TRUE(std::filesystem::exists(set.dir.path() / "report" / "positions.svg"));
  EXPECT_FALSE(std::filesystem::exists(set.dir.path() / "report" / "field.svg"));
  EXPECT_EQ(set.page.find("Field distortion"), std::string::npos);
  // Every pair: its offset from the nominal one and its overlap NCC as --json holds them, and its status.
  ASSERT_EQ(json["pairs"].size(), 12u);
  for (const auto& pair : json["pairs"]) {
    ASSERT_TRUE(pair["accepted"].get<bool>());
    EXPECT_TRUE(Shows(set.page, fmt::format("{:.3f}", pair["dx_px"].get<double>()))) << pair.dump();
    EXPECT_TRUE(Shows(set.page, fmt::format("{:.3f}", pair["dy_px"].get<double>()))) << pair.dump();
    EXPECT_TRUE(Shows(set.page, fmt::format("{:.3f}", pair["overlap_ncc"].get<double>()))) << pair.dump();
  }
  EXPECT_NE(set.page.find(fmt::format("<td>{:.3f}</td>", json["mean_overlap_ncc"].get<double>())), std::string::npos);
  EXPECT_NE(set.page.find(fmt::format("Birge ratio {:.3f}", json["loop_birge_ratio"].get<double>())), std::string::npos);
  // Every tile's position and u, as the positions CSV has them.
  const std::string csv = PositionsCsv(set.stitched);
  for (size_t i = 0; i < set.stitched.files.size(); ++i) {
    const Eigen::Vector2d& p = set.stitched.PositionsPx()[i];
    EXPECT_TRUE(Shows(set.page, fmt::format("{:.3f}", p.x())));
    EXPECT_TRUE(Shows(set.page, fmt::format("{:.3f}", p.y())));
    EXPECT_TRUE(Shows(set.page, set.stitched.files[i]));
  }
  // Four squares of four tiles in a 3 x 3 grid, each closing to within a few pair uncertainties.
  const size_t loops = set.page.find("<h2>Loop misclosures</h2>");
  ASSERT_NE(loops, std::string::npos);
  const std::string loop_table = set.page.substr(loops, set.page.find("</table>", loops) - loops);
  size_t rows = 0;
  for (size_t at = loop_table.find("<tr><td>"); at != std::string::npos; at = loop_table.find("<tr><td>", at + 1)) ++rows;
  EXPECT_EQ(rows, 4u);
}

TEST(StitchReport, ShowsTheFieldWithItsTermsAndTheOverlapCorrelationBeforeAndAfter) {
  StitchedSet set;
  StitchAndReport(set, true);
  const nlohmann::ordered_json& field = set.summary.json["distortion"];
  EXPECT_TRUE(std::filesystem::exists(set.dir.path() / "report" / "field.svg"));
  EXPECT_NE(set.page.find("Field distortion terms"), std::string::npos);
  for (const auto& term : field["terms"]) {
    const std::string row = fmt::format("<td>{}</td><td>{:.4f}</td><td>{:.4f}</td>", term["name"].get<std::string>(),
                                        term["value_px"].get<double>(), term["u_px"].get<double>());
    EXPECT_NE(set.page.find(row), std::string::npos) << row;
  }
  EXPECT_NE(set.page.find(fmt::format("{:.3f} / {:.3f}", field["overlap_ncc_before"].get<double>(),
                                      field["overlap_ncc_after"].get<double>())),
            std::string::npos);
  const double largest = field["largest_displacement_px"].get<double>();
  EXPECT_NE(set.page.find(fmt::format("{:.3f} px ({:.3f} um)", largest, largest * 0.001 * 1e3)), std::string::npos);
  // The positions on the page are the undistorted tiles'.
  const Eigen::Vector2d& last = set.stitched.field->fit.positions_px.back();
  EXPECT_TRUE(Shows(set.page, fmt::format("{:.3f}", last.x())));
}

}  // namespace
}  // namespace fvm::workflows
