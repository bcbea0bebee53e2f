#include "report/stitch_report.h"

#include <fmt/format.h>
#include <plplot.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "report/support.h"

namespace fvm::report {
namespace {

PLINT PairColour(StitchReportData::PairStatus status) {
  switch (status) {
    case StitchReportData::PairStatus::kAccepted:
      return kAfter;
    case StitchReportData::PairStatus::kOverruled:
      return kBefore;
    default:
      return kMuted;
  }
}

// The tiles where they were placed (outlines, numbered), each neighbour pair a line between the two tiles' centres:
// accepted blue, overruled by the loops vermilion, unresolved grey and dashed. Image frame: x right, y down.
std::string RenderPositions(const StitchReportData& data) {
  const double w = data.width_px, h = data.height_px;
  double x0 = 0, x1 = w, y0 = 0, y1 = h;
  for (const StitchReportData::Tile& t : data.tiles) {
    x0 = std::min(x0, t.x_px), x1 = std::max(x1, t.x_px + w), y0 = std::min(y0, t.y_px), y1 = std::max(y1, t.y_px + h);
  }
  const double margin = 0.04 * std::max(x1 - x0, y1 - y0);
  x0 -= margin, x1 += margin, y0 -= margin, y1 += margin;
  SvgPlot plot(900, 760);
  plvpas(0.14, 0.95, 0.1, 0.86, (y1 - y0) / (x1 - x0));
  plwind(x0, x1, y1, y0);  // y grows downwards, as in the tiles
  Frame("bcnst", XTick(x0, x1), 0, "bcnstv", 0, 0);
  plwidth(0.8);
  plcol0(kMuted);
  for (const StitchReportData::Tile& t : data.tiles) {
    std::array<PLFLT, 5> x = {t.x_px, t.x_px + w, t.x_px + w, t.x_px, t.x_px};
    std::array<PLFLT, 5> y = {t.y_px, t.y_px, t.y_px + h, t.y_px + h, t.y_px};
    plline(5, x.data(), y.data());
  }
  plwidth(2.2);
  for (const StitchReportData::Pair& p : data.pairs) {
    const StitchReportData::Tile& a = data.tiles[static_cast<size_t>(p.a)];
    const StitchReportData::Tile& b = data.tiles[static_cast<size_t>(p.b)];
    plcol0(PairColour(p.status));
    pllsty(p.status == StitchReportData::PairStatus::kUnresolved ? 2 : 1);
    pljoin(a.x_px + w / 2, a.y_px + h / 2, b.x_px + w / 2, b.y_px + h / 2);
  }
  pllsty(1);
  plwidth(1.0);
  plcol0(kInk);
  plschr(0, 0.7);
  for (const StitchReportData::Tile& t : data.tiles) plptex(t.x_px + w / 2, t.y_px + h / 2 - 0.08 * h, 1, 0, 0.5, PlText(t.label).c_str());
  plschr(0, 1.0);
  pllab("x (px)", "", "");
  YLabel("y (px, down)", TickChars(y0, y1, NiceCeil((y1 - y0) / 6)));
  FittedMtex("t", 2.6, 0.5, 0.5, fmt::format("{} tiles where they were placed, and their neighbour pairs", data.tiles.size()), 0.95);
  plschr(0, 0.8);
  plcol0(kAfter);
  plmtex("t", 0.8, 0.2, 0.5, "accepted");
  plcol0(kBefore);
  plmtex("t", 0.8, 0.5, 0.5, "overruled by the loops");
  plcol0(kMuted);
  plmtex("t", 0.8, 0.8, 0.5, "unresolved (dashed)");
  plschr(0, 1.0);
  return plot.Finish();
}

// The field's displacement across one tile, arrows magnified to a round scale the subtitle states.
std::string RenderField(const StitchReportData& data) {
  const double w = data.width_px, h = data.height_px;
  double largest = 0;
  for (const StitchReportData::Displacement& d : data.field) largest = std::max(largest, std::hypot(d.dx_px, d.dy_px));
  // The longest arrow about 12 % of the tile's width, about one spacing of the arrows.
  const double scale = largest > 0 ? NiceFloor(0.12 * w / largest) : 1.0;
  const double margin = 0.13 * w;  // room for the arrows at the edges
  SvgPlot plot(800, static_cast<PLINT>(std::clamp(800.0 * h / w, 400.0, 1200.0)));
  plvpas(0.14, 0.95, 0.1, 0.86, (h + 2 * margin) / (w + 2 * margin));
  plwind(-margin, w + margin, h + margin, -margin);
  Frame("bcnst", XTick(-margin, w + margin), 0, "bcnstv", 0, 0);
  plcol0(kMuted);
  std::array<PLFLT, 5> x = {0, w, w, 0, 0}, y = {0, 0, h, h, 0};
  plline(5, x.data(), y.data());
  plcol0(kAfter);
  for (const StitchReportData::Displacement& d : data.field) {
    // Arrow's head in world units; y is flipped on the page, which Arrow's equal scales tolerate as a mirror.
    Arrow(d.x_px, d.y_px, scale * d.dx_px, scale * d.dy_px, 0.02 * w);
  }
  plcol0(kInk);
  pllab("tile x (px)", "", "");
  YLabel("tile y (px, down)", TickChars(-margin, h + margin, NiceCeil((h + 2 * margin) / 6)));
  FittedMtex("t", 2.6, 0.5, 0.5, "The objective's field distortion across a tile", 0.95);
  plschr(0, 0.8);
  FittedMtex("t", 1.0, 0.5, 0.5, fmt::format("{}; arrows magnified {:g} times", data.field_caption, scale), 0.95);
  plschr(0, 1.0);
  return plot.Finish();
}

std::string RenderStitchPage(const StitchReportData& data) {
  std::string html = HtmlHead(data.title.empty() ? "fvm stitch" : data.title) + HtmlKeyValueTable(data.summary);
  html += HtmlFigure("positions.svg", "Tiles and pairs", "The tiles where they were placed, with their neighbour pairs",
                     "Each tile's outline at its position (x right, y down, the first tile's corner at 0, 0), numbered "
                     "in the layout's order; a line joins the centres of two neighbours: blue where their pair was "
                     "accepted, vermilion where the grid's loops overruled it, grey and dashed where it placed nothing.");
  if (!data.field.empty()) {
    html += HtmlFigure("field.svg", "Field distortion", "The field distortion's displacement across one tile",
                       "Where each pixel of a tile sees the part, against an undistorted image: the same for every tile "
                       "of the objective, identified from the overlaps with the positions; arrows magnified as the "
                       "subtitle says. Its terms with their standard uncertainties are in the table below.");
  }
  for (const StitchReportData::Table& t : data.tables) {
    html += "<h2>" + HtmlEscape(t.heading) + "</h2>\n";
    if (!t.note.empty()) html += "<p>" + HtmlEscape(t.note) + "</p>\n";
    html += HtmlTable(t.header, t.rows);
  }
  return html + HtmlTail();
}

}  // namespace

void WriteStitchReport(const std::filesystem::path& dir, const StitchReportData& data) {
  std::vector<std::pair<std::string, std::string>> files = {{"positions.svg", RenderPositions(data)}};
  if (!data.field.empty()) files.emplace_back("field.svg", RenderField(data));
  files.emplace_back("index.html", RenderStitchPage(data));
  WriteReportFiles(dir, files);
}

}  // namespace fvm::report
