// The shared parts of the reports: PLplot's C API into SVG, one PLplot stream per plot, and a plain HTML page that
// shows the plots with <img>, so the directory can be copied, mailed or archived as it is.

#include "report/support.h"

#include <fmt/format.h>
#include <stdlib.h>  // mkstemps
#include <unistd.h>  // close

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "core/file_io.h"
#include "core/input_error.h"

namespace fvm::report {
namespace {

namespace fs = std::filesystem;

void SetPalette() {
  plscmap0n(kColourCount);
  plscol0a(kBackground, 255, 255, 255, 1.0);
  plscol0a(kInk, 0, 0, 0, 1.0);
  plscol0a(kGrid, 225, 225, 225, 1.0);
  plscol0a(kMuted, 120, 120, 120, 1.0);
  plscol0a(kBefore, 213, 94, 0, 1.0);
  plscol0a(kAfter, 0, 114, 178, 1.0);
  plscol0a(kBeforeFill, 213, 94, 0, 0.35);
  plscol0a(kAfterFill, 0, 114, 178, 0.35);
  const std::array<std::array<int, 3>, kSeriesCount> series = {{{0, 158, 115}, {230, 159, 0}, {204, 121, 167}}};
  for (int i = 0; i < kSeriesCount; ++i) {
    const auto& [r, g, b] = series[static_cast<std::size_t>(i)];
    plscol0a(kSeries0 + i, r, g, b, 1.0);
    plscol0a(kSeriesFill0 + i, r, g, b, 0.2);
  }
}

bool XmlDecodable(std::uint32_t c) {
  return c >= 0x20 && c != '<' && c != '>' && c != '&' && c != '"' && c != '\'' && (c < 0xD800 || c > 0xDFFF) &&
         c != 0xFFFE && c != 0xFFFF && c <= 0x10FFFF;
}

void AppendUtf8(std::string& out, std::uint32_t c) {
  if (c < 0x80) {
    out += static_cast<char>(c);
  } else if (c < 0x800) {
    out += static_cast<char>(0xC0 | (c >> 6));
    out += static_cast<char>(0x80 | (c & 0x3F));
  } else if (c < 0x10000) {
    out += static_cast<char>(0xE0 | (c >> 12));
    out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (c & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (c >> 18));
    out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (c & 0x3F));
  }
}

// PLplot's svg driver writes every character of a text as a reference (&#x4d;). Decoding them, all but XML's
// special characters, makes the labels searchable in the file (and by tests) and the file smaller; it stays UTF-8.
std::string DecodeCharacterReferences(std::string_view svg) {
  std::string out;
  out.reserve(svg.size());
  std::size_t i = 0;
  while (i < svg.size()) {
    if (svg.compare(i, 3, "&#x") == 0) {
      const std::size_t end = svg.find(';', i + 3);
      std::uint32_t c = 0;
      if (end != std::string_view::npos && end > i + 3 && end - i - 3 <= 6) {
        const auto [ptr, ec] = std::from_chars(svg.data() + i + 3, svg.data() + end, c, 16);
        if (ec == std::errc() && ptr == svg.data() + end && XmlDecodable(c)) {
          AppendUtf8(out, c);
          i = end + 1;
          continue;
        }
      }
    }
    out += svg[i++];
  }
  return out;
}

// A PLplot installation without its svg driver would make plinit() ask for a device on stdin; fail clearly instead.
void RequireSvgDriver() {
  static const bool available = [] {
    std::array<const char*, 128> menu{}, names{};
    const char** menu_ptr = menu.data();
    const char** names_ptr = names.data();
    int count = static_cast<int>(names.size());
    plgDevs(&menu_ptr, &names_ptr, &count);
    return std::any_of(names.begin(), names.begin() + std::clamp(count, 0, static_cast<int>(names.size())),
                       [](const char* name) { return name != nullptr && std::string_view(name) == "svg"; });
  }();
  if (!available) {
    throw std::runtime_error(
        "PLplot has no svg driver: install the Debian package 'libplplot17' (it holds plplot5.15.0/drivers/svg.so), "
        "or point PLPLOT_DRV_DIR at the folder that holds svg.so");
  }
}

std::size_t CodePoints(std::string_view text) {
  return static_cast<std::size_t>(
      std::count_if(text.begin(), text.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

fs::path MakeTempFile() {
  std::string name = (fs::temp_directory_path() / "fvm-plot-XXXXXX.svg").string();
  const int fd = mkstemps(name.data(), 4);
  if (fd < 0) {
    throw std::system_error(errno, std::generic_category(), "cannot create a temporary file for a plot: " + name);
  }
  close(fd);
  return name;
}

}  // namespace

namespace fs = std::filesystem;

// PLplot reads '#' as the start of an escape sequence; text from the caller (parameter names) is shown literally.
std::string PlText(std::string_view text) {
  std::string out;
  for (const char c : text) {
    out += c;
    if (c == '#') out += '#';
  }
  return out;
}

std::string UnitLabel(std::string_view unit) {
  for (const std::string_view micro : {"urad", "um"}) {
    if (unit.starts_with(micro)) return "µ" + PlText(unit.substr(1));  // also "um/min", "urad/K"
  }
  return PlText(unit);
}

// 1, 2 or 5 times a power of ten: the steps and scales people read at a glance.
double NiceCeil(double x) {
  const double power = std::pow(10.0, std::floor(std::log10(x)));
  for (const double m : {1.0, 2.0, 5.0}) {
    if (m * power >= x * (1 - 1e-12)) return m * power;
  }
  return 10 * power;
}

double NiceFloor(double x) {
  const double power = std::pow(10.0, std::floor(std::log10(x)));
  for (const double m : {5.0, 2.0}) {
    if (m * power <= x * (1 + 1e-12)) return m * power;
  }
  return power;
}

std::vector<double> Finite(const std::vector<double>& values) {
  std::vector<double> out;
  std::copy_if(values.begin(), values.end(), std::back_inserter(out), [](double v) { return std::isfinite(v); });
  return out;
}

SvgPlot::SvgPlot(PLINT width_px, PLINT height_px) : width_px_(width_px), height_px_(height_px) {
  RequireSvgDriver();
  temp_ = MakeTempFile();
  plgstrm(&caller_stream_);
  plmkstrm(&stream_);
  if (stream_ < 0) {
    plsstrm(caller_stream_);
    RemoveTemp();
    throw std::runtime_error("PLplot has no free plot stream left for the report");
  }
  plsdev("svg");
  plsfnam(temp_.c_str());
  plspage(0, 0, width_px, height_px, 0, 0);
  SetPalette();
  plinit();
  pladv(0);
  plcol0(kInk);
}

SvgPlot::~SvgPlot() {
  End();
  RemoveTemp();
}

std::string SvgPlot::Finish() {
  End();
  std::ifstream in(temp_, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in || text.str().find("</svg>") == std::string::npos) {
    throw std::runtime_error("PLplot did not finish the plot in " + temp_.string());
  }
  return DecodeCharacterReferences(text.str());
}

void SvgPlot::End() {
  if (stream_ < 0) return;
  plsstrm(stream_);
  plend1();  // frees the stream and closes the file
  stream_ = -1;
  plsstrm(caller_stream_);
}

void SvgPlot::RemoveTemp() {
  std::error_code ignored;
  fs::remove(temp_, ignored);
}

// Grid lines under the data, then the frame with ticks and numbers.
void Frame(const char* x_options, PLFLT x_tick, PLINT x_sub, const char* y_options, PLFLT y_tick, PLINT y_sub,
           bool grid) {
  if (grid) {
    plcol0(kGrid);
    plwidth(0.8);
    plbox("g", x_tick, x_sub, "g", y_tick, y_sub);
  }
  plcol0(kInk);
  plwidth(1.0);
  plbox(x_options, x_tick, x_sub, y_options, y_tick, y_sub);
}

// An arrow from (x, y) to (x + dx, y + dy) in world coordinates with equal scales on both axes.
void Arrow(PLFLT x, PLFLT y, PLFLT dx, PLFLT dy, PLFLT max_head) {
  const PLFLT length = std::hypot(dx, dy);
  if (!(length > 0)) return;
  const PLFLT head = std::min(0.35 * length, max_head);
  const PLFLT ux = dx / length, uy = dy / length;
  const PLFLT bx = x + dx - ux * head, by = y + dy - uy * head;
  pljoin(x, y, bx, by);
  std::array<PLFLT, 3> hx = {x + dx, bx - uy * 0.4 * head, bx + uy * 0.4 * head};
  std::array<PLFLT, 3> hy = {y + dy, by + ux * 0.4 * head, by - ux * 0.4 * head};
  plfill(3, hx.data(), hy.data());
}

void Disc(PLFLT x, PLFLT y, PLFLT radius) {
  constexpr int kSides = 16;
  std::array<PLFLT, kSides> px, py;
  for (int i = 0; i < kSides; ++i) {
    const double angle = 2 * std::numbers::pi * i / kSides;
    px[i] = x + radius * std::cos(angle);
    py[i] = y + radius * std::sin(angle);
  }
  plfill(kSides, px.data(), py.data());
}

int TickChars(double lo, double hi, double tick) {
  const double largest = std::max(std::abs(lo), std::abs(hi));
  const int integer_digits = largest >= 1 ? static_cast<int>(std::floor(std::log10(largest))) + 1 : 1;
  const int decimals = tick > 0 && tick < 1 ? static_cast<int>(std::ceil(-std::log10(tick) - 1e-9)) : 0;
  return (lo < 0 ? 1 : 0) + integer_digits + (decimals > 0 ? 1 + decimals : 0);
}

double XTick(double lo, double hi) {
  const double span = hi - lo;
  if (!(span > 0)) return 1.0;
  PLFLT vx0, vx1, vy0, vy1, sx0, sx1, sy0, sy1, default_mm, height_mm;
  plgvpd(&vx0, &vx1, &vy0, &vy1);
  plgspa(&sx0, &sx1, &sy0, &sy1);
  plgchr(&default_mm, &height_mm);
  const double width_mm = (vx1 - vx0) * (sx1 - sx0);
  double tick = NiceCeil(span / 12);
  for (int i = 0; i < 12; ++i) {
    // A digit is 0.85 character heights wide (see YLabel), and a character height apart from the next number.
    const double needed_mm = 0.85 * height_mm * TickChars(lo, hi, tick) + height_mm;
    if (tick / span * width_mm >= needed_mm) break;
    tick = NiceCeil(tick * 1.01);
  }
  return tick;
}

// Measured on PLplot's svg output: a font size is 4/3 of the character height that plmtex displacements count in,
// the tick numbers end half a character height from the frame, and a digit of DejaVu Sans is 0.64 of the font size
// wide (0.85 character heights); the label's own half height and a gap make the rest.
void YLabel(const std::string& text, int tick_chars) {
  plmtex("l", 1.9 + 0.85 * tick_chars, 0.5, 0.5, text.c_str());
}

void FittedMtex(const char* side, PLFLT disp, PLFLT pos, PLFLT just, const std::string& text, double width_fraction,
                double line_step) {
  PLFLT default_mm, height_mm, x0, x1, y0, y1;
  plgchr(&default_mm, &height_mm);
  plgspa(&x0, &x1, &y0, &y1);
  // A character is about 0.6 of the font size wide (0.8 character heights; see YLabel).
  const double available_mm = width_fraction * (x1 - x0);
  const auto needed_mm = [&](std::string_view line) { return 0.8 * height_mm * static_cast<double>(CodePoints(line)); };
  std::vector<std::string> lines = {text};
  if (line_step > 0 && needed_mm(text) > available_mm) {
    std::size_t best = std::string::npos;
    for (std::size_t i = text.find(' '); i != std::string::npos; i = text.find(' ', i + 1)) {
      const auto off_centre = [&](std::size_t k) { return std::abs(static_cast<double>(k) - text.size() / 2.0); };
      if (best == std::string::npos || off_centre(i) < off_centre(best)) best = i;
    }
    if (best != std::string::npos) lines = {text.substr(0, best), text.substr(best + 1)};
  }
  double widest = 0;
  for (const std::string& line : lines) widest = std::max(widest, needed_mm(line));
  const double scale = height_mm / default_mm;
  const double shrink = widest > available_mm ? available_mm / widest : 1.0;
  plschr(0, scale * shrink);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    // The displacement counts in the (smaller) character heights; the first of two lines goes further out.
    const double out = disp + (lines.size() == 2 && i == 0 ? line_step : 0.0);
    plmtex(side, out / shrink, pos, just, lines[i].c_str());
  }
  plschr(0, scale);
}

std::string HtmlEscape(std::string_view text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string HtmlHead(std::string_view title) {
  return fmt::format(
      "<!DOCTYPE html>\n"
      "<html lang=\"en\">\n"
      "<head>\n"
      "<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      "<title>{0}</title>\n"
      "<style>\n"
      "body {{ font-family: sans-serif; color: #222; max-width: 1000px; margin: 2em auto; padding: 0 1em; }}\n"
      "h1 {{ font-size: 1.5em; }}\n"
      "h2 {{ font-size: 1.2em; margin-top: 2em; }}\n"
      "table {{ border-collapse: collapse; }}\n"
      "th, td {{ text-align: left; padding: 0.25em 1em 0.25em 0; border-bottom: 1px solid #ddd; "
      "vertical-align: top; }}\n"
      "th {{ font-weight: normal; color: #555; }}\n"
      "td {{ font-variant-numeric: tabular-nums; }}\n"
      "figure {{ margin: 0; }}\n"
      "img {{ max-width: 100%; height: auto; }}\n"
      "figcaption {{ color: #444; margin-top: 0.5em; }}\n"
      "</style>\n"
      "</head>\n"
      "<body>\n"
      "<h1>{0}</h1>\n",
      HtmlEscape(title));
}

std::string HtmlTail() { return "</body>\n</html>\n"; }

std::string HtmlKeyValueTable(const std::vector<std::pair<std::string, std::string>>& rows) {
  if (rows.empty()) return "";
  std::string html = "<table>\n";
  for (const auto& [key, value] : rows) {
    html += fmt::format("<tr><th scope=\"row\">{}</th><td>{}</td></tr>\n", HtmlEscape(key), HtmlEscape(value));
  }
  return html + "</table>\n";
}

std::string HtmlTable(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  std::string html = "<table>\n<tr>";
  for (const std::string& h : header) html += fmt::format("<th scope=\"col\">{}</th>", HtmlEscape(h));
  html += "</tr>\n";
  for (const auto& row : rows) {
    html += "<tr>";
    for (const std::string& cell : row) html += fmt::format("<td>{}</td>", HtmlEscape(cell));
    html += "</tr>\n";
  }
  return html + "</table>\n";
}

std::string HtmlFigure(std::string_view file, std::string_view heading, std::string_view alt, std::string_view caption) {
  return fmt::format("<h2>{}</h2>\n<figure>\n<img src=\"{}\" alt=\"{}\">\n<figcaption>{}</figcaption>\n</figure>\n",
                     HtmlEscape(heading), HtmlEscape(file), HtmlEscape(alt), HtmlEscape(caption));
}

void WriteReportFiles(const fs::path& dir, const std::vector<std::pair<std::string, std::string>>& files) {
  const auto error = [&dir](const std::string& why) {
    return InputError(
        fmt::format("cannot write the report to '{}': {}; choose a directory you can write", dir.string(), why));
  };

  // The outermost directory this call creates, so a failure can take back exactly what it made.
  std::error_code ec;
  fs::path target = dir.lexically_normal();
  if (!target.has_filename()) target = target.parent_path();  // "out/" names "out"
  fs::path first_created;
  for (fs::path p = target; !p.empty() && !fs::exists(p, ec) && !ec; p = p.parent_path()) {
    first_created = p;
    if (p == p.parent_path()) break;
  }
  fs::create_directories(dir, ec);
  if (ec) throw error(ec.message());
  if (!fs::is_directory(dir, ec)) throw error("it exists and is not a directory");

  std::vector<fs::path> created;
  try {
    for (const auto& [name, content] : files) {
      const fs::path path = dir / name;
      const bool is_new = !fs::exists(path, ec);
      WriteFileAtomically(path, content);
      if (is_new) created.push_back(path);
    }
  } catch (const std::exception& e) {
    for (const fs::path& path : created) fs::remove(path, ec);
    if (!first_created.empty()) {
      for (fs::path p = target; fs::remove(p, ec) && p != first_created; p = p.parent_path()) {
      }
    }
    throw error(e.what());
  }
}

}  // namespace fvm::report
