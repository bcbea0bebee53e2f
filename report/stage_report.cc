// The report of `fvm calibrate` and `fvm diagnose`: its three plots and its page (the shared parts, PLplot into SVG
// and the HTML skeleton, are in report/support.h).

#include "report/stage_report.h"

#include <fmt/format.h>
#include <plplot.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/histogram.h"
#include "report/support.h"

namespace fvm::report {
namespace {

namespace fs = std::filesystem;

bool IsFinite(const ReportData::ErrorVector& e) {
  return std::isfinite(e.x_mm) && std::isfinite(e.y_mm) && std::isfinite(e.dx_um) && std::isfinite(e.dy_um);
}

// ---- distance errors: two histograms on one pair of axes ----------------------------------------------------

struct Histogram {
  std::vector<int> counts;
  int max_count = 0;
};

Histogram Bin(const std::vector<double>& values, double first_edge, double width, int bins) {
  Histogram h{BinCounts(values, first_edge, width, bins)};
  for (const int count : h.counts) h.max_count = std::max(h.max_count, count);
  return h;
}

void DrawHistogram(const Histogram& h, double first_edge, double width, PLINT fill, PLINT line) {
  std::vector<PLFLT> x = {first_edge}, y = {0};
  for (std::size_t i = 0; i < h.counts.size(); ++i) {
    x.insert(x.end(), {first_edge + width * static_cast<double>(i), first_edge + width * static_cast<double>(i + 1)});
    y.insert(y.end(), 2, h.counts[i]);
  }
  x.push_back(x.back());
  y.push_back(0);
  plcol0(fill);
  plfill(static_cast<PLINT>(x.size()), x.data(), y.data());
  plcol0(line);
  plwidth(1.6);
  plline(static_cast<PLINT>(x.size()), x.data(), y.data());
  plwidth(1.0);
}

// One panel: the errors binned about zero on their own bins (about 30 across the largest error), so a bias shows as
// an offset from the centre line and errors a hundred times smaller than the others still fill their panel.
void DrawDistancePanel(const std::vector<double>& values, const std::string& what, PLINT fill, PLINT line,
                       double vp_y0, double vp_y1) {
  double extent = 0;
  for (const double v : values) extent = std::max(extent, std::abs(v));
  if (!(extent > 0)) extent = 1.0;  // no data, or all exact: still a readable +-1 um axis
  const double width = NiceCeil(2 * extent / 30);
  const int half_bins = std::max(1, static_cast<int>(std::ceil(extent / width - 1e-9)));
  const double first_edge = -half_bins * width;
  const Histogram h = Bin(values, first_edge, width, 2 * half_bins);
  const double y_max = std::max(1, h.max_count) * 1.1;
  const double y_tick = std::max(1.0, NiceCeil(y_max / 5));
  const PLINT y_sub = y_tick <= 5 ? static_cast<PLINT>(y_tick) : 0;  // minor ticks on whole counts only

  plvpor(0.1, 0.96, vp_y0, vp_y1);
  plwind(first_edge, -first_edge, 0, y_max);
  const double x_tick = XTick(first_edge, -first_edge);
  Frame("", x_tick, 0, "", y_tick, y_sub);
  plcol0(kMuted);
  pllsty(2);
  pljoin(0, 0, 0, y_max);
  pllsty(1);
  if (!values.empty()) DrawHistogram(h, first_edge, width, fill, line);
  Frame("bcnst", x_tick, 0, "bcnstv", y_tick, y_sub, false);
  pllab("distance error (µm)", "", "");
  YLabel("count", TickChars(0, y_max, y_tick));
  FittedMtex("t", 2.4, 0.5, 0.5, PlText(what), 0.86, 1.5);
  plschr(0, 0.85);
  const std::string numbers =
      values.empty() ? std::string("no distance errors")
                     : fmt::format("n = {}, RMS {:.3g} µm, max |e| {:.3g} µm; bins {:g} µm wide", values.size(),
                                   Rms(values), extent, width);
  plmtex("t", 0.9, 0.5, 0.5, numbers.c_str());
  plschr(0, 1.0);
}

// Before above after, each on its own axes: after a compensation the errors are far smaller than before.
std::string RenderDistanceErrors(const ReportData& data) {
  SvgPlot plot(900, 900);
  DrawDistancePanel(Finite(data.distance_errors_before_um), "Distance errors before " + data.change, kBeforeFill,
                    kBefore, 0.61, 0.87);
  DrawDistancePanel(Finite(data.distance_errors_after_um), "Distance errors after " + data.change, kAfterFill, kAfter,
                    0.1, 0.36);
  return plot.Finish();
}

// ---- lateral error vectors over the stage area --------------------------------------------------------------

double MaxLength(const std::vector<ReportData::ErrorVector>& errors) {
  double longest = 0;
  for (const auto& e : errors) {
    if (IsFinite(e)) longest = std::max(longest, std::hypot(e.dx_um, e.dy_um));
  }
  return longest;
}

struct StageWindow {
  double x0, x1, y0, y1;  // world coordinates of the frame, mm
  double span;            // of the positions and the travel, mm
};

StageWindow StageWindowOf(const ReportData& data) {
  const ReportData::StageArea& area = data.stage_area;
  double x0 = area.x_min_mm, x1 = area.x_max_mm, y0 = area.y_min_mm, y1 = area.y_max_mm;
  for (const auto* errors : {&data.errors_before, &data.errors_after}) {
    for (const auto& e : *errors) {
      if (!IsFinite(e)) continue;
      x0 = std::min(x0, e.x_mm), x1 = std::max(x1, e.x_mm), y0 = std::min(y0, e.y_mm), y1 = std::max(y1, e.y_mm);
    }
  }
  double span = std::max(x1 - x0, y1 - y0);
  if (!(span > 0)) span = 1.0;
  // A margin so arrows at the edge of the travel stay inside the frame.
  const double margin = 0.06 * span;
  return {x0 - margin, x1 + margin, y0 - margin, y1 + margin, span};
}

// One panel: the stage travel to scale, the positions, the arrows on this panel's own magnification (the longest
// arrow 4 to 10 % of the span, a round factor), and below the frame the scale arrow and the magnification.
void DrawVectorPanel(const ReportData& data, const std::vector<ReportData::ErrorVector>& errors, const StageWindow& w,
                     const std::string& what, PLINT colour, double vx0, double vx1, int width_px, int height_px) {
  const ReportData::StageArea& area = data.stage_area;
  plvpas(vx0, vx1, 0.22, 0.85, (w.y1 - w.y0) / (w.x1 - w.x0));
  plwind(w.x0, w.x1, w.y0, w.y1);
  const double tick = NiceCeil(w.span / 5), x_tick = std::max(tick, XTick(w.x0, w.x1));
  Frame("bcnst", x_tick, 0, "bcnstv", tick, 0);
  pllab("stage x (mm)", "", "");
  YLabel("stage y (mm)", TickChars(w.y0, w.y1, tick));
  FittedMtex("t", 2.4, 0.5, 0.5, PlText(what), vx1 - vx0, 1.5);

  plcol0(kMuted);
  pllsty(2);
  const std::array<PLFLT, 5> rx = {area.x_min_mm, area.x_max_mm, area.x_max_mm, area.x_min_mm, area.x_min_mm};
  const std::array<PLFLT, 5> ry = {area.y_min_mm, area.y_min_mm, area.y_max_mm, area.y_max_mm, area.y_min_mm};
  plline(5, rx.data(), ry.data());
  pllsty(1);

  for (const auto& e : errors) {
    if (IsFinite(e)) Disc(e.x_mm, e.y_mm, 0.004 * w.span);
  }
  const double longest = MaxLength(errors);
  const double mm_per_um = longest > 0 ? NiceFloor(0.1 * w.span / longest) : 0.0;
  const double max_head = 0.018 * w.span;
  plcol0(colour);
  plwidth(1.4);
  for (const auto& e : errors) {
    if (IsFinite(e)) Arrow(e.x_mm, e.y_mm, e.dx_um * mm_per_um, e.dy_um * mm_per_um, max_head);
  }
  plwidth(1.0);
  plcol0(kInk);
  plschr(0, 0.85);
  plmtex("t", 0.9, 0.5, 0.5,
         errors.empty() ? "no lateral errors"
                        : fmt::format("{} positions, longest error {:.3g} µm", errors.size(), longest).c_str());

  // The scale strip below the frame, in the panel's mm: the scale arrow, the magnification.
  PLFLT px0, px1, py0, py1;
  plgvpd(&px0, &px1, &py0, &py1);
  const double strip_y0 = 0.015, strip_y1 = 0.105;
  const double mm_per_px = (w.x1 - w.x0) / ((px1 - px0) * width_px);
  plvpor(px0, px1, strip_y0, strip_y1);
  plwind(w.x0, w.x1, 0, (strip_y1 - strip_y0) * height_px * mm_per_px);
  const double strip_mm = (strip_y1 - strip_y0) * height_px * mm_per_px, gap = 8 * mm_per_px;
  const double row = 0.72 * strip_mm;
  plptex(w.x0, 0.25 * strip_mm, 1, 0, 0,
         fmt::format("dashed: stage travel {:g} × {:g} mm", area.x_max_mm - area.x_min_mm, area.y_max_mm - area.y_min_mm)
             .c_str());
  if (longest > 0) {
    const double scale_um = NiceFloor(longest);
    plcol0(colour);
    plwidth(1.4);
    Arrow(w.x0, row, scale_um * mm_per_um, 0, max_head);
    plwidth(1.0);
    plcol0(kInk);
    plptex(w.x0 + scale_um * mm_per_um + gap, row, 1, 0, 0,
           fmt::format("{:g} µm; arrows magnified × {:g}", scale_um, 1000 * mm_per_um).c_str());
  }
  plschr(0, 1.0);
}

// Before and after side by side, each with its own arrow scale: after a compensation the residual pattern is what
// a user wants to see next, and at the scale of the errors before it would be invisible.
std::string RenderErrorVectors(const ReportData& data) {
  const StageWindow w = StageWindowOf(data);
  constexpr int kWidth = 1500, kHeight = 900;
  SvgPlot plot(kWidth, kHeight);
  DrawVectorPanel(data, data.errors_before, w, "Lateral errors before " + data.change, kBefore, 0.1, 0.48, kWidth,
                  kHeight);
  DrawVectorPanel(data, data.errors_after, w, "Lateral errors after " + data.change, kAfter, 0.6, 0.98, kWidth,
                  kHeight);
  return plot.Finish();
}

// ---- parameters with +-2u, one panel per unit ---------------------------------------------------------------

struct UnitGroup {
  std::string unit;
  std::vector<const ReportData::Parameter*> parameters;
};

// Micrometres first, then microradians, then any other unit in the order it first appears.
std::vector<UnitGroup> GroupByUnit(const std::vector<ReportData::Parameter>& parameters) {
  std::vector<UnitGroup> groups = {{"um", {}}, {"urad", {}}};
  for (const auto& p : parameters) {
    if (!std::isfinite(p.value)) continue;
    auto it = std::find_if(groups.begin(), groups.end(), [&](const UnitGroup& g) { return g.unit == p.unit; });
    if (it == groups.end()) it = groups.insert(groups.end(), UnitGroup{p.unit, {}});
    it->parameters.push_back(&p);
  }
  std::erase_if(groups, [](const UnitGroup& g) { return g.parameters.empty(); });
  return groups;
}

void DrawParameterPanel(const UnitGroup& group, double vp_y0, double vp_y1) {
  const auto n = static_cast<PLINT>(group.parameters.size());
  std::vector<PLFLT> x, value, low, high;
  double y_min = 0, y_max = 0;
  for (PLINT i = 0; i < n; ++i) {
    const ReportData::Parameter& p = *group.parameters[static_cast<std::size_t>(i)];
    const double band = std::isfinite(p.uncertainty) ? 2 * std::abs(p.uncertainty) : 0.0;
    x.push_back(i + 1);
    value.push_back(p.value);
    low.push_back(p.value - band);
    high.push_back(p.value + band);
    y_min = std::min(y_min, low.back());
    y_max = std::max(y_max, high.back());
  }
  if (!(y_max > y_min)) y_min = -1, y_max = 1;
  const double pad = 0.08 * (y_max - y_min);
  y_min -= pad, y_max += pad;

  plvpor(0.13, 0.98, vp_y0, vp_y1);
  plwind(0.5, n + 0.5, y_min, y_max);
  plcol0(kGrid);
  plwidth(0.8);
  for (PLINT i = 1; i <= n; ++i) pljoin(i, y_min, i, y_max);  // guides from each name up to its value
  const double y_tick = NiceCeil((y_max - y_min) / 6);
  plsyax(7, 0);  // plain numbers up to 7 digits: PLplot's "(x10³)" would sit on the axis label
  Frame("", 1.0, 0, "", y_tick, 0);  // vertical grid lines at the parameters only
  plcol0(kMuted);
  pljoin(0.5, 0, n + 0.5, 0);
  plcol0(kAfter);
  plwidth(1.6);
  plerry(n, x.data(), low.data(), high.data());
  plwidth(1.0);
  plschr(0, 0.7);
  plstring(n, x.data(), value.data(), "●");
  plschr(0, 1.0);
  Frame("bct", 1.0, 1, "bcnstv", y_tick, 0, false);
  for (PLINT i = 0; i < n; ++i) {
    plmtex("bv", 0.8, (i + 0.5) / n, 1.0, PlText(group.parameters[static_cast<std::size_t>(i)]->name).c_str());
  }
  const std::string unit = UnitLabel(group.unit);
  FittedMtex("t", 2.0, 0.5, 0.5, fmt::format("Parameters in {}: value with ± 2u error bars (k = 2)", unit), 0.8);
  YLabel(fmt::format("value ({})", unit), TickChars(y_min, y_max, y_tick));
  plsyax(0, 0);
}

std::string RenderParameters(const ReportData& data) {
  const std::vector<UnitGroup> groups = GroupByUnit(data.parameters);
  // Below each panel its parameter names, written downwards: room for the longest (about 16 px a character on a
  // page this tall).
  std::size_t longest = 0;
  for (const ReportData::Parameter& p : data.parameters) longest = std::max(longest, p.name.size());
  const int kNamesPx = std::max(85, 40 + 17 * static_cast<int>(longest)), kPanelPx = 330 + kNamesPx, kTitlePx = 65;
  const int panels = std::max(1, static_cast<int>(groups.size()));
  const int height = panels * kPanelPx;
  SvgPlot plot(1000, height);
  if (groups.empty()) {
    plvpor(0.13, 0.98, static_cast<double>(kNamesPx) / height, 1.0 - static_cast<double>(kTitlePx) / height);
    plwind(0, 1, 0, 1);
    Frame("bc", 0, 0, "bc", 0, 0, false);
    pllab("", "", "Parameters: value with ± 2u error bars (k = 2)");
    plcol0(kMuted);
    plptex(0.5, 0.5, 1, 0, 0.5, "no parameters in this report");
    return plot.Finish();
  }
  for (int i = 0; i < panels; ++i) {
    const int top_px = i * kPanelPx;  // from the top of the page
    const double vp_y1 = 1.0 - static_cast<double>(top_px + kTitlePx) / height;
    const double vp_y0 = 1.0 - static_cast<double>(top_px + kPanelPx - kNamesPx) / height;
    DrawParameterPanel(groups[static_cast<std::size_t>(i)], vp_y0, vp_y1);
  }
  return plot.Finish();
}

// ---- the forward selection: mean residuals after each step ------------------------------------------------------

std::string RenderSteps(const ReportData& data) {
  const std::vector<ReportData::Step>& steps = data.steps;
  const PLINT n = static_cast<PLINT>(steps.size());
  double top = 0;
  for (const ReportData::Step& s : steps) {
    for (const double v : {s.identification_um, s.held_out_um}) {
      if (std::isfinite(v)) top = std::max(top, v);
    }
  }
  if (!(top > 0)) top = 1.0;
  const double y_max = top * 1.25;  // headroom for the legend
  const double y_tick = NiceCeil(y_max / 6);
  SvgPlot plot(800, 560);
  plvpor(0.1, 0.96, 0.2, 0.9);
  plwind(-0.5, n - 0.5, 0, y_max);
  Frame("", 1.0, 0, "", y_tick, 0);  // vertical grid lines at the steps only
  Frame("bc", 0, 0, "bcnstv", y_tick, 0, false);
  for (PLINT i = 0; i < n; ++i) {
    plcol0(kInk);
    plmtex("b", 1.2 + 1.1 * (i % 2), (i + 0.5) / n, 0.5, PlText(steps[static_cast<std::size_t>(i)].label).c_str());
  }
  pllab("", "mean 3-D residual (µm)", "Mean 3-D residual after each step of the forward selection");
  plmtex("b", 4.2, 0.5, 0.5, "model: the base, then each effect in the order added");
  // Held-out values are written above their points, identification values below, so close ones stay apart.
  struct Series {
    double ReportData::Step::*member;
    PLINT colour;
    double label_offset;  // of y_max
  };
  const std::array<Series, 2> series = {Series{&ReportData::Step::held_out_um, kSeries0 + 0, 0.025},
                                        Series{&ReportData::Step::identification_um, kSeries0 + 1, -0.06}};
  for (const auto& [member, colour, label_offset] : series) {
    std::vector<PLFLT> x, y;
    for (PLINT i = 0; i < n; ++i) {
      const double v = steps[static_cast<std::size_t>(i)].*member;
      if (!std::isfinite(v)) continue;
      x.push_back(i);
      y.push_back(v);
    }
    plcol0(colour);
    plwidth(2.0);
    plline(static_cast<PLINT>(x.size()), x.data(), y.data());
    plwidth(1.0);
    for (std::size_t k = 0; k < x.size(); ++k) {
      plptex(x[k] + 0.04 * n, y[k] + label_offset * y_max, 1, 0, 0, fmt::format("{:.3g}", y[k]).c_str());
      plpoin(1, &x[k], &y[k], 17);
    }
  }
  const std::array<const char*, 2> texts = {"held-out placements", "identification"};
  const std::array<PLINT, 2> options = {PL_LEGEND_LINE, PL_LEGEND_LINE};
  const std::array<PLINT, 2> text_colours = {kInk, kInk}, colours = {kSeries0 + 0, kSeries0 + 1}, styles = {1, 1};
  const std::array<PLFLT, 2> widths = {2, 2};
  PLFLT legend_width, legend_height;
  pllegend(&legend_width, &legend_height, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
           PL_POSITION_TOP | PL_POSITION_RIGHT | PL_POSITION_INSIDE, 0.02, 0.03, 0.08, kBackground, kGrid, 1, 0, 0, 2,
           options.data(), 1.0, 0.85, 2.0, 0.0, text_colours.data(), texts.data(), nullptr, nullptr, nullptr, nullptr,
           colours.data(), styles.data(), widths.data(), nullptr, nullptr, nullptr, nullptr);
  return plot.Finish();
}

// alt and caption name what separates before from after as {0} (ReportData::change).
struct Figure {
  const char* file;
  const char* heading;
  const char* alt;
  const char* caption;
};

constexpr std::array<Figure, 3> kFigures = {{
    {"distance_errors.svg", "Distance errors", "Histogram of distance errors before and after {0}",
     "Errors of the distances between calotte pairs before (vermilion, above) and after (blue, below) {0}, in "
     "micrometres; each panel has its own bins and axes, so read the numbers on the axes."},
    {"error_vectors.svg", "Lateral error vectors",
     "Lateral error vectors at their stage positions before and after {0}",
     "Lateral errors (dx, dy) drawn as arrows at their stage positions before (vermilion, left) and after "
     "(blue, right) {0}, over the stage travel drawn to scale; each panel magnifies its arrows by its own "
     "factor, given under it with a scale arrow."},
    {"parameters.svg", "Parameters", "Identified parameters with error bars of two standard uncertainties",
     "Identified parameter values with error bars of plus and minus two standard uncertainties (k = 2), one "
     "panel per unit."},
}};

constexpr Figure kStepsFigure = {
    "steps.svg", "Step by step", "Mean residuals of the identification data and the held-out placements after each step",
    "Mean 3-D residual of the identification centres and of the held-out placements (which the selection never fits) "
    "for the base model and after each effect added, in the order they were added."};

std::string RenderHtml(const ReportData& data) {
  std::string html = HtmlHead(data.title.empty() ? "fvm report" : data.title) + HtmlKeyValueTable(data.summary);
  if (!data.steps.empty()) html += HtmlFigure(kStepsFigure.file, kStepsFigure.heading, kStepsFigure.alt, kStepsFigure.caption);
  for (const Figure& f : kFigures) {
    const auto retell = [&](const char* text) { return fmt::format(fmt::runtime(text), data.change); };
    html += HtmlFigure(f.file, f.heading, retell(f.alt), retell(f.caption));
  }
  return html + HtmlTail();
}

}  // namespace

void WriteReport(const fs::path& dir, const ReportData& data) {
  // Everything is drawn before DIR is touched, so a failure while plotting leaves nothing behind either. The page
  // goes last, so it never refers to a plot that is not there yet.
  std::vector<std::pair<std::string, std::string>> files = {
      {kFigures[0].file, RenderDistanceErrors(data)},
      {kFigures[1].file, RenderErrorVectors(data)},
      {kFigures[2].file, RenderParameters(data)},
  };
  if (!data.steps.empty()) files.emplace_back(kStepsFigure.file, RenderSteps(data));
  files.emplace_back("index.html", RenderHtml(data));
  WriteReportFiles(dir, files);
}

}  // namespace fvm::report
