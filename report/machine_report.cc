// The machine-tool report of `fvm verify --report`: drawn with the shared PLplot and HTML parts of
// report/support.h.

#include "report/machine_report.h"

#include <fmt/format.h>
#include <plplot.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "report/support.h"

namespace fvm::report {
namespace {


// ---- error functions: a row per axis, translations left, rotations right ---------------------------------------

void DrawFunctionPanel(const MachineReportData::AxisFunctions& axis, const std::vector<MachineReportData::Curve>& curves,
                       const char* unit, double vx0, double vx1, double vy0, double vy1) {
  const std::vector<double>& x = axis.position_mm;
  double y_min = 0, y_max = 0;
  for (const auto& c : curves) {
    for (std::size_t i = 0; i < c.value.size() && i < c.u.size(); ++i) {
      if (!std::isfinite(c.value[i]) || !std::isfinite(c.u[i])) continue;
      y_min = std::min(y_min, c.value[i] - 2 * c.u[i]);
      y_max = std::max(y_max, c.value[i] + 2 * c.u[i]);
    }
  }
  if (!(y_max > y_min)) y_min = -1, y_max = 1;
  const double pad = 0.08 * (y_max - y_min);
  y_min -= pad, y_max += pad;
  const double x0 = x.empty() ? 0.0 : x.front(), x1 = x.empty() ? 1.0 : x.back();

  // One character size for everything in the panel, so PLplot's fixed offsets (in character heights) keep the tick
  // numbers, the axis labels and the curve names apart.
  plschr(0, 0.85);
  plvpor(vx0, vx1, vy0, vy1);
  plwind(x0, x1 > x0 ? x1 : x0 + 1, y_min, y_max);
  const double x_tick = XTick(x0, x1), y_tick = NiceCeil((y_max - y_min) / 6);
  Frame("", x_tick, 0, "", y_tick, 0);
  plcol0(kMuted);
  pljoin(x0, 0, x1, 0);
  for (std::size_t s = 0; s < curves.size() && s < kSeriesCount; ++s) {
    const MachineReportData::Curve& c = curves[s];
    const std::size_t n = std::min({x.size(), c.value.size(), c.u.size()});
    if (n < 2) continue;
    // The band: the upper edge forwards, the lower edge back.
    std::vector<PLFLT> bx, by;
    for (std::size_t i = 0; i < n; ++i) bx.push_back(x[i]), by.push_back(c.value[i] + 2 * c.u[i]);
    for (std::size_t i = n; i-- > 0;) bx.push_back(x[i]), by.push_back(c.value[i] - 2 * c.u[i]);
    plcol0(static_cast<PLINT>(kSeriesFill0 + static_cast<int>(s)));
    plfill(static_cast<PLINT>(bx.size()), bx.data(), by.data());
    plcol0(static_cast<PLINT>(kSeries0 + static_cast<int>(s)));
    plwidth(1.8);
    plline(static_cast<PLINT>(n), x.data(), c.value.data());
    plwidth(1.0);
    plmtex("t", 0.6, 0.02 + 0.13 * static_cast<double>(s), 0, PlText(c.name).c_str());
  }
  plcol0(kInk);
  // Numbered ticks on x that stand apart: positions of four digits run into each other at PLplot's own choice.
  Frame("bcnst", x_tick, 0, "bcnstv", y_tick, 0, false);
  const bool translations = std::string(unit) == "um";
  pllab(fmt::format("{} position (mm)", axis.axis).c_str(), "", "");
  YLabel(fmt::format("error ({})", UnitLabel(unit)), TickChars(y_min, y_max, y_tick));
  plmtex("t", 0.6, 1.0, 1.0, fmt::format("{} {}", axis.axis, translations ? "translations" : "rotations").c_str());
  plschr(0, 1.0);
}

std::string RenderErrorFunctions(const MachineReportData& data) {
  // A row per axis: above each pair of panels the curve names and panel titles (kAbovePx), below them the tick
  // numbers and the position label (kBelowPx), so a row's position label never meets the next row's names.
  constexpr int kWidth = 1200, kRowPx = 380, kTopPx = 60, kAbovePx = 45, kBelowPx = 85;
  const int height = kTopPx + 3 * kRowPx;
  SvgPlot plot(kWidth, height);
  plvpor(0, 1, 0, 1);
  plwind(0, 1, 0, 1);
  plschr(0, 0.85);
  plmtex("t", -1.5, 0.5, 0.5, "Error functions relative to the axis origin, 95 % bands (k = 2)");
  plschr(0, 1.0);
  for (int row = 0; row < 3; ++row) {
    const double top = 1.0 - static_cast<double>(kTopPx + row * kRowPx + kAbovePx) / height;
    const double bottom = 1.0 - static_cast<double>(kTopPx + (row + 1) * kRowPx - kBelowPx) / height;
    const auto& axis = data.functions[static_cast<std::size_t>(row)];
    DrawFunctionPanel(axis, axis.translations, "um", 0.1, 0.45, bottom, top);
    DrawFunctionPanel(axis, axis.rotations, "urad", 0.6, 0.95, bottom, top);
  }
  return plot.Finish();
}

// ---- volumetric errors, sorted --------------------------------------------------------------------------------

std::vector<double> Sorted(const std::vector<MachineReportData::PointError>& points, bool after) {
  std::vector<double> out;
  for (const auto& p : points) out.push_back(after ? p.after_um : p.before_um);
  out = Finite(out);
  std::sort(out.begin(), out.end());
  return out;
}

std::string RenderVolumetricErrors(const MachineReportData& data) {
  struct Series {
    std::vector<double> values;
    PLINT colour, style;
    std::string label;
  };
  std::vector<Series> series;
  const auto add = [&](const std::vector<MachineReportData::PointError>& points, const char* what, PLINT style) {
    if (points.empty()) return;
    series.push_back({Sorted(points, false), kBefore, style, fmt::format("{}, before", what)});
    series.push_back({Sorted(points, true), kAfter, style, fmt::format("{}, after", what)});
  };
  add(data.readings, "readings", 1);
  add(data.validation, "validation", 2);
  double y_max = 0, smallest = HUGE_VAL, under_key = 0;
  for (const auto& s : series) {
    if (s.values.empty()) continue;
    y_max = std::max(y_max, s.values.back());
    for (const double v : s.values) {
      if (v > 0) smallest = std::min(smallest, v);
    }
    // The key sits top left, over the first 70 % of the sorted points and above 72 % of the axis: the axis goes high
    // enough that no curve reaches it there (sorted, they are low on the left unless the errors are all alike).
    under_key = std::max(under_key, s.values[static_cast<std::size_t>(0.7 * static_cast<double>(s.values.size() - 1))]);
  }
  // Errors after an identification twenty times smaller than before lie flat on zero on a linear axis: then the
  // axis is logarithmic, whole decades from the decade of the smallest error.
  const bool log_axis = y_max > 0 && smallest < y_max / 20;
  double y_min = 0;
  const auto y_of = [&](double v) { return log_axis ? std::log10(std::max(v, std::pow(10.0, y_min))) : v; };
  if (log_axis) {
    y_min = std::floor(std::log10(smallest));
    y_max = std::ceil(std::log10(1.1 * y_max));
    y_max = std::max(y_max, std::ceil(y_min + (std::log10(std::max(under_key, smallest)) - y_min) / 0.7));
  } else {
    y_max = y_max > 0 ? NiceCeil(std::max(1.1 * y_max, under_key / 0.7)) : 1.0;
  }
  const char* y_options = log_axis ? "bcnstvl" : "bcnstv";

  SvgPlot plot(900, 560);
  plvpor(0.1, 0.96, 0.12, 0.9);
  plwind(0, 100, y_min, y_max);
  Frame("", 0, 0, "", 0, 0);
  for (const auto& s : series) {
    const std::size_t n = s.values.size();
    if (n == 0) continue;
    // Each point at the share of points with a smaller error: sets of different sizes share the axis.
    std::vector<PLFLT> x, y;
    for (std::size_t i = 0; i < n; ++i) {
      x.push_back(n == 1 ? 50.0 : 100.0 * static_cast<double>(i) / static_cast<double>(n - 1));
      y.push_back(y_of(s.values[i]));
    }
    plcol0(s.colour);
    pllsty(s.style);
    plwidth(1.8);
    plline(static_cast<PLINT>(n), x.data(), y.data());
    plwidth(1.0);
    pllsty(1);
  }
  Frame("bcnst", 0, 0, y_options, 0, 0, false);
  pllab("share of points (%), sorted by error", log_axis ? "volumetric error (µm), log scale" : "volumetric error (µm)",
        "Volumetric error of every point before and after the identification");
  plschr(0, 0.8);
  for (std::size_t i = 0; i < series.size(); ++i) {
    const Series& s = series[i];
    plcol0(s.colour);
    const double y = y_min + (y_max - y_min) * (0.94 - 0.065 * static_cast<double>(i));
    pllsty(s.style);
    plwidth(1.8);
    pljoin(3, y, 9, y);
    plwidth(1.0);
    pllsty(1);
    plcol0(kInk);
    const double max = s.values.empty() ? 0.0 : s.values.back();
    double mean = 0;
    for (const double v : s.values) mean += v / static_cast<double>(s.values.size());
    plptex(11, y, 1, 0, 0, fmt::format("{}: n = {}, mean {:.3g} µm, max {:.3g} µm", s.label, s.values.size(), mean, max).c_str());
  }
  plschr(0, 1.0);
  return plot.Finish();
}

// ---- error map: XY and XZ views, discs sized by the error -------------------------------------------------------

double Error(const MachineReportData::PointError& p, bool after) { return after ? p.after_um : p.before_um; }

// One view (vertical 1: XY from above, 2: XZ from the front) of one state (before or after): a disc at each point,
// radius proportional to its error, the largest drawn first so small ones on top stay visible.
void DrawMapPanel(const std::vector<MachineReportData::PointError>& points, int vertical, bool after, double mm_per_um,
                  double vx0, double vx1, double vy0, double vy1) {
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  bool first = true;
  const auto coordinate = [](const MachineReportData::PointError& p, int k) { return k == 0 ? p.x_mm : k == 1 ? p.y_mm : p.z_mm; };
  for (const auto& p : points) {
    const double x = p.x_mm, y = coordinate(p, vertical);
    if (first) x0 = x1 = x, y0 = y1 = y, first = false;
    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  }
  const double span = std::max({x1 - x0, y1 - y0, 1.0});
  const double margin = 0.08 * span;
  plvpas(vx0, vx1, vy0, vy1, (y1 - y0 + 2 * margin) / (x1 - x0 + 2 * margin));
  plwind(x0 - margin, x1 + margin, y0 - margin, y1 + margin);
  const double tick = NiceCeil(span / 5), x_tick = std::max(tick, XTick(x0 - margin, x1 + margin));
  Frame("bcnst", x_tick, 0, "bcnstv", tick, 0);
  std::vector<const MachineReportData::PointError*> order;
  for (const auto& p : points) order.push_back(&p);
  std::sort(order.begin(), order.end(), [after](const auto* a, const auto* b) { return Error(*a, after) > Error(*b, after); });
  for (const auto* p : order) {
    const double e = Error(*p, after);
    if (!(std::isfinite(e) && e > 0)) continue;
    plcol0(after ? kAfterFill : kBeforeFill);
    Disc(p->x_mm, coordinate(*p, vertical), e * mm_per_um);
  }
  plcol0(kInk);
  pllab("machine x (mm)", "", vertical == 1 ? "XY view, from above" : "XZ view, from the front");
  YLabel(fmt::format("machine {} (mm)", "xyz"[vertical]), TickChars(y0 - margin, y1 + margin, tick));
}

// Before (the ideal machine) on the left, after (the identified model) on the right, each on its own disc scale:
// after an identification the errors left are what a user wants to see next, invisible at the scale of before.
std::string RenderErrorMap(const MachineReportData& data) {
  const bool held_out = !data.validation.empty();
  const std::vector<MachineReportData::PointError>& points = held_out ? data.validation : data.readings;
  double x0 = 0, x1 = 0;
  for (const auto& p : points) x0 = std::min(x0, p.x_mm), x1 = std::max(x1, p.x_mm);
  const double span = std::max(x1 - x0, 1.0);

  constexpr int kHeight = 1150;
  SvgPlot plot(1400, kHeight);
  plschr(0, 0.8);
  const auto from_top = [&](int px) { return 1.0 - static_cast<double>(px) / kHeight; };
  for (const bool after : {false, true}) {
    double largest = 0, sum = 0;
    std::size_t n = 0;
    for (const auto& p : points) {
      const double e = Error(p, after);
      if (!std::isfinite(e)) continue;
      largest = std::max(largest, e), sum += e, ++n;
    }
    // The largest disc has a radius of 3 to 6 % of the x span, on a round scale.
    const double mm_per_um = largest > 0 ? NiceFloor(0.06 * span / largest) : 0.0;
    const double vx0 = after ? 0.61 : 0.11, vx1 = after ? 0.97 : 0.47;
    DrawMapPanel(points, 1, after, mm_per_um, vx0, vx1, 0.55, from_top(270));
    DrawMapPanel(points, 2, after, mm_per_um, vx0, vx1, 0.1, 0.36);
    // The column's heading, its numbers and its scale, between the figure's title and the XY view's title.
    plvpor(0, 1, 0, 1);
    plwind(0, 1, 0, 1);
    const double centre = 0.5 * (vx0 + vx1);
    plcol0(after ? kAfter : kBefore);
    plptex(centre, from_top(100), 1, 0, 0.5, after ? "After: the identified model" : "Before: the ideal machine");
    plcol0(kInk);
    plschr(0, 0.7);
    const double mean = n ? sum / static_cast<double>(n) : 0.0;
    plptex(centre, from_top(135), 1, 0, 0.5, fmt::format("mean {:.3g} µm, max {:.3g} µm", mean, largest).c_str());
    plptex(centre, from_top(163), 1, 0, 0.5, fmt::format("disc radius {:g} mm per µm", mm_per_um).c_str());
    plschr(0, 0.8);
  }
  plmtex("t", -1.5, 0.5, 0.5, fmt::format("Volumetric error at the {} points", held_out ? "validation" : "fitted").c_str());
  plschr(0, 1.0);
  return plot.Finish();
}

// ---- the page -------------------------------------------------------------------------------------------------

std::string RenderMachinePage(const MachineReportData& data) {
  std::string html = HtmlHead(data.title.empty() ? "fvm verify" : data.title) + HtmlKeyValueTable(data.summary);
  for (const MachineReportData::Table& t : data.tables) {
    html += "<h2>" + HtmlEscape(t.heading) + "</h2>\n";
    if (!t.note.empty()) html += "<p>" + HtmlEscape(t.note) + "</p>\n";
    html += HtmlTable(t.header, t.rows);
  }
  html += HtmlFigure("error_functions.svg", "Error functions",
                     "The 18 translation and rotation error functions, one row per axis, with 95 % bands",
                     "Each axis' translation (µm, left) and rotation (µrad, right) error functions over its travel, "
                     "relative to their value at the axis origin (the tracker pose absorbs constants), with bands of "
                     "two standard uncertainties from the coefficient covariance (k = 2, about 95 %). Squareness is in "
                     "the table above.");
  html += HtmlFigure("volumetric_errors.svg", "Volumetric errors",
                     "Volumetric errors of the points before and after the identification, sorted",
                     "The volumetric error (distance between a reading and the model's prediction) of every point, "
                     "sorted: the ideal machine (before, vermilion) and the identified one (after, blue); readings "
                     "solid, validation points dashed.");
  html += HtmlFigure("error_map.svg", "Error map", "Volumetric errors over the workspace, seen from above and from the front",
                     "Discs at the points, radius proportional to the volumetric error, before (vermilion, left) and "
                     "after (blue, right) the identification, in an XY and an XZ view of the workspace; each side has "
                     "its own disc scale, given under its heading.");
  return html + HtmlTail();
}

}  // namespace

void WriteMachineReport(const std::filesystem::path& dir, const MachineReportData& data) {
  WriteReportFiles(dir, {
                            {"error_functions.svg", RenderErrorFunctions(data)},
                            {"volumetric_errors.svg", RenderVolumetricErrors(data)},
                            {"error_map.svg", RenderErrorMap(data)},
                            {"index.html", RenderMachinePage(data)},
                        });
}

}  // namespace fvm::report
