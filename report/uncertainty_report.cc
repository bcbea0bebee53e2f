#include "report/uncertainty_report.h"

#include <fmt/format.h>
#include <plplot.h>

#include <algorithm>
#include <cmath>

#include "core/number_text.h"
#include "core/histogram.h"
#include "report/support.h"

namespace fvm::report {
namespace {


// Histograms of the per-run mean errors: final (after) and validation (series colour), on one axis.
std::string RenderDistribution(const UncertaintyReportData& data) {
  double lo = 1e300, hi = 0;
  for (const std::vector<double>* v : {&data.final_mean_um, &data.validation_mean_um}) {
    for (double x : *v) lo = std::min(lo, x), hi = std::max(hi, x);
  }
  if (!(hi > lo)) lo = std::max(0.0, lo - 1), hi = lo + 2;
  const double span = hi - lo;
  lo -= 0.05 * span, hi += 0.05 * span;
  constexpr int kBins = 40;
  std::vector<PLFLT> centres(kBins);
  for (int b = 0; b < kBins; ++b) centres[static_cast<size_t>(b)] = lo + (b + 0.5) * (hi - lo) / kBins;
  const auto counts = [&](const std::vector<double>& v) {
    const std::vector<int> n = BinCounts(v, lo, (hi - lo) / kBins, kBins);
    return std::vector<PLFLT>(n.begin(), n.end());
  };
  const std::vector<PLFLT> final_counts = counts(data.final_mean_um), validation_counts = counts(data.validation_mean_um);
  double top = 1;
  for (double c : final_counts) top = std::max(top, c);
  for (double c : validation_counts) top = std::max(top, c);

  SvgPlot plot(900, 560);
  plvpor(0.1, 0.96, 0.12, 0.85);
  const double y_max = 1.1 * top, y_tick = std::max(1.0, NiceCeil(y_max / 6));  // counts: whole ticks
  plwind(lo, hi, 0, y_max);
  Frame("", 0, 0, "", y_tick, 0);
  plwidth(1.8);
  plcol0(kAfter);
  plbin(kBins, centres.data(), final_counts.data(), PL_BIN_CENTRED | PL_BIN_NOEXPAND);
  if (!data.validation_mean_um.empty()) {
    plcol0(kSeries0);
    plbin(kBins, centres.data(), validation_counts.data(), PL_BIN_CENTRED | PL_BIN_NOEXPAND);
  }
  plwidth(1.0);
  Frame("bcnst", 0, 0, "bcnstv", y_tick, 0, false);
  pllab("mean volumetric error of a run (µm)", "", "");
  YLabel("number of runs", TickChars(0, y_max, y_tick));
  plmtex("t", 2.6, 0.5, 0.5, fmt::format("Distribution over the {} Monte Carlo runs", data.final_mean_um.size()).c_str());
  // The key between the title and the frame, where it hides no bar.
  plschr(0, 0.8);
  const bool validation = !data.validation_mean_um.empty();
  plcol0(kAfter);
  plmtex("t", 0.8, validation ? 0.25 : 0.5, 0.5, "final: the run's own readings");
  if (validation) {
    plcol0(kSeries0);
    plmtex("t", 0.8, 0.75, 0.5, "validation points");
  }
  plschr(0, 1.0);
  return plot.Finish();
}

// XY view: each point's 95 % ellipsoid seen from above (the shadow of the ellipsoid x^T C^-1 x = chi^2_3(0.95) on the
// XY plane is the ellipse of C's XY block at the same level), magnified to a common scale.
std::string RenderU95Map(const UncertaintyReportData& data) {
  constexpr double kChi2Of3At95 = 7.814727903251178;
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1, largest = 0;
  for (size_t i = 0; i < data.points.size(); ++i) {
    const auto& p = data.points[i];
    if (i == 0) x0 = x1 = p.x_mm, y0 = y1 = p.y_mm;
    x0 = std::min(x0, p.x_mm), x1 = std::max(x1, p.x_mm), y0 = std::min(y0, p.y_mm), y1 = std::max(y1, p.y_mm);
    largest = std::max(largest, p.semi_axis_um[2]);
  }
  const double span = std::max({x1 - x0, y1 - y0, 1.0}), margin = 0.1 * span;
  // The largest semi-axis 3 to 6 % of the span, on a round scale that the subtitle states.
  const double mm_per_um = largest > 0 ? NiceFloor(0.06 * span / largest) : 1.0;
  SvgPlot plot(800, 800);
  plvpas(0.12, 0.95, 0.1, 0.87, (y1 - y0 + 2 * margin) / (x1 - x0 + 2 * margin));
  plwind(x0 - margin, x1 + margin, y0 - margin, y1 + margin);
  const double x_tick = XTick(x0 - margin, x1 + margin);
  Frame("bcnst", x_tick, 0, "bcnstv", 0, 0);
  for (const auto& p : data.points) {
    // The XY block's principal axes: a x a^T + ... by the closed form of a symmetric 2 x 2 eigen decomposition.
    const double a = p.covariance_xy_um2[0], b = p.covariance_xy_um2[1], c = p.covariance_xy_um2[2];
    const double mean = 0.5 * (a + c), diff = std::hypot(0.5 * (a - c), b);
    const double major = std::sqrt(std::max(0.0, kChi2Of3At95 * (mean + diff)));
    const double minor = std::sqrt(std::max(0.0, kChi2Of3At95 * (mean - diff)));
    const double angle = 0.5 * std::atan2(2 * b, a - c);
    constexpr int kSides = 48;
    std::vector<PLFLT> x(kSides), y(kSides);
    for (int k = 0; k < kSides; ++k) {
      const double t = 2 * M_PI * k / kSides;
      const double u = major * std::cos(t), v = minor * std::sin(t);
      x[static_cast<size_t>(k)] = p.x_mm + mm_per_um * (u * std::cos(angle) - v * std::sin(angle));
      y[static_cast<size_t>(k)] = p.y_mm + mm_per_um * (u * std::sin(angle) + v * std::cos(angle));
    }
    plcol0(kAfterFill);
    plfill(kSides, x.data(), y.data());
    plcol0(kAfter);
    x.push_back(x.front()), y.push_back(y.front());
    plline(kSides + 1, x.data(), y.data());
  }
  plcol0(kInk);
  pllab("machine x (mm)", "machine y (mm)", "");
  FittedMtex("t", 2.6, 0.5, 0.5, "95 % ellipsoids seen from above (all z levels)", 0.95);
  plschr(0, 0.8);
  plmtex("t", 1.0, 0.5, 0.5,
         fmt::format("largest semi-axis {:.3g} µm; 1 µm drawn as {:g} mm", largest, mm_per_um).c_str());
  plschr(0, 1.0);
  return plot.Finish();
}

std::string PointsCsv(const UncertaintyReportData& data) {
  std::string out = "id,x,y,z,U95_um,semi_axis1_um,semi_axis2_um,semi_axis3_um\n";
  for (const auto& p : data.points) {
    out += fmt::format("{},{},{},{},{:.4f},{:.4f},{:.4f},{:.4f}\n", p.id, FormatShortest(p.x_mm), FormatShortest(p.y_mm),
                       FormatShortest(p.z_mm), p.u95_um, p.semi_axis_um[0], p.semi_axis_um[1], p.semi_axis_um[2]);
  }
  return out;
}

std::string RunsCsv(const UncertaintyReportData& data) {
  std::string out = data.validation_mean_um.empty() ? "run,final_mean_um\n" : "run,final_mean_um,validation_mean_um\n";
  for (size_t i = 0; i < data.final_mean_um.size(); ++i) {
    out += fmt::format("{},{:.4f}", i, data.final_mean_um[i]);
    if (!data.validation_mean_um.empty()) out += fmt::format(",{:.4f}", data.validation_mean_um[i]);
    out += "\n";
  }
  return out;
}

std::string RenderUncertaintyPage(const UncertaintyReportData& data) {
  std::string html = HtmlHead(data.title.empty() ? "fvm uncertainty" : data.title) + HtmlKeyValueTable(data.summary);
  html += HtmlFigure("distribution.svg", "Distribution over the runs", "Histograms of the runs' mean errors",
                     "Each run draws the readings again with the tracker's noise around the identified machine and "
                     "identifies them afresh: the mean error on its own readings (final) and on the validation points.");
  html += HtmlFigure("u95_map.svg", "95 % ellipsoid per point", "Each point's 95 % ellipsoid seen from above",
                     "The ellipsoid around the identified prediction of each point that holds 95 % of the runs' "
                     "predictions (normal approximation, chi-square with 3 degrees of freedom), seen from above and "
                     "magnified to the common scale given under the title; points.csv lists its semi-axes and the radius that holds 95 % of "
                     "the runs.");
  html += "<p>Numbers: <a href=\"points.csv\">points.csv</a>, <a href=\"runs.csv\">runs.csv</a>.</p>\n";
  return html + HtmlTail();
}

}  // namespace

void WriteUncertaintyReport(const std::filesystem::path& dir, const UncertaintyReportData& data) {
  WriteReportFiles(dir, {
                            {"points.csv", PointsCsv(data)},
                            {"runs.csv", RunsCsv(data)},
                            {"distribution.svg", RenderDistribution(data)},
                            {"u95_map.svg", RenderU95Map(data)},
                            {"index.html", RenderUncertaintyPage(data)},
                        });
}

}  // namespace fvm::report
