#pragma once
// What the reports of fvm share (report/stage_report.cc for `fvm calibrate`/`diagnose`, report/machine_report.cc for
// `fvm verify`): PLplot into SVG, one stream per plot; the palette; axis helpers; the HTML page skeleton and its
// tables; writing a report directory atomically. Internal to the report library.

#include <plplot.h>

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/statistics.h"

namespace fvm::report {

// Indices into PLplot's colour map 0. Before and after use the Okabe-Ito vermilion and blue, which stay apart for
// colour-blind readers and in greyscale print; the three series colours (Okabe-Ito bluish green, orange, reddish
// purple) tell apart curves that are neither.
enum Colour : PLINT {
  kBackground = 0,
  kInk = 1,
  kGrid = 2,
  kMuted = 3,
  kBefore = 4,
  kAfter = 5,
  kBeforeFill = 6,
  kAfterFill = 7,
  kSeries0 = 8,  // kSeries0 + i, i < 3: a curve; kSeriesFill0 + i: its band
  kSeriesFill0 = 11,
  kColourCount = 14,
};
inline constexpr int kSeriesCount = 3;

// PLplot reads '#' as the start of an escape sequence; text from the caller (parameter names) is shown literally.
std::string PlText(std::string_view text);
std::string UnitLabel(std::string_view unit);  // "um" -> "µm", "urad" -> "µrad"
// 1, 2 or 5 times a power of ten at or above / at or below x (> 0): the steps and scales people read at a glance.
double NiceCeil(double x);
double NiceFloor(double x);
std::vector<double> Finite(const std::vector<double>& values);

// One plot: its own PLplot stream rendering to a temporary SVG file, so plots never share state with each other
// or with a stream the caller has open. PLplot's device writes to a file by name, hence the temporary file.
class SvgPlot {
 public:
  SvgPlot(PLINT width_px, PLINT height_px);
  SvgPlot(const SvgPlot&) = delete;
  SvgPlot& operator=(const SvgPlot&) = delete;
  ~SvgPlot();

  PLINT width_px() const { return width_px_; }
  PLINT height_px() const { return height_px_; }

  // Ends the plot and returns the SVG document.
  std::string Finish();

 private:
  void End();
  void RemoveTemp();

  PLINT width_px_, height_px_;
  std::filesystem::path temp_;
  PLINT caller_stream_ = 0;
  PLINT stream_ = -1;
};

// Grid lines under the data, then the frame with ticks and numbers.
void Frame(const char* x_options, PLFLT x_tick, PLINT x_sub, const char* y_options, PLFLT y_tick, PLINT y_sub,
           bool grid = true);
// An arrow from (x, y) to (x + dx, y + dy) in world coordinates with equal scales on both axes.
void Arrow(PLFLT x, PLFLT y, PLFLT dx, PLFLT dy, PLFLT max_head);
// A filled disc (a 16-gon) in world coordinates with equal scales on both axes.
void Disc(PLFLT x, PLFLT y, PLFLT radius);

// The characters of the longest number PLplot writes at the ticks (step `tick`, a NiceCeil value) of an axis from lo
// to hi: sign, integer digits, the point and decimals.
int TickChars(double lo, double hi, double tick);
// The step of the numbered ticks on the x axis of the current viewport, from lo to hi: the finest NiceCeil step whose
// numbers, at the current character size, stand at least a character height apart.
double XTick(double lo, double hi);
// The y-axis label, parallel to the axis and centred on it, far enough out to clear horizontal tick numbers ("v") of
// up to `tick_chars` characters at the current character size (pllab's fixed place clears four).
void YLabel(const std::string& text, int tick_chars);

// plmtex at the current character size, so that the text fits `width_fraction` of the page's width: first broken
// at the space nearest its middle into two lines (the first `line_step` character heights further out), when
// line_step > 0; then shrunk (never grown). Long titles (diagnose's list of added effects) stay on the page.
void FittedMtex(const char* side, PLFLT disp, PLFLT pos, PLFLT just, const std::string& text, double width_fraction,
                double line_step = 0);

// ---- the page ----
std::string HtmlEscape(std::string_view text);
// <!DOCTYPE html> ... <body><h1>title</h1>: the page up to its content, with the reports' style sheet.
std::string HtmlHead(std::string_view title);
std::string HtmlTail();  // </body></html>
// A two-column table: a header cell per row, then its value. Empty rows: nothing.
std::string HtmlKeyValueTable(const std::vector<std::pair<std::string, std::string>>& rows);
// A table with a header row; every row has as many cells as the header.
std::string HtmlTable(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows);
// <h2>heading</h2> and a figure showing `file` with its alt text and caption (all escaped here).
std::string HtmlFigure(std::string_view file, std::string_view heading, std::string_view alt, std::string_view caption);

// Writes the files (name, content) into DIR, creating it if needed, each atomically and in the order given (put
// the page last, so it never refers to a plot that is not there yet). Throws fvm::InputError naming DIR when it
// cannot be written, and then leaves no file or directory it created behind.
void WriteReportFiles(const std::filesystem::path& dir, const std::vector<std::pair<std::string, std::string>>& files);

}  // namespace fvm::report
