#pragma once
// Where the text of an SVG picture lands, estimated from its <text> elements the way a reader's renderer places
// them: the x, y (baseline) and text-anchor of each text, its font-size, and every transform from the root down.
// What the estimate can see: text on text (a title over a panel title, an axis label on a legend) and text past the
// canvas (a unit cut off at the left). What it cannot: text over lines, discs or arrows (the data), and glyph shapes;
// widths are a conservative per-character figure for DejaVu Sans (what `sans-serif` is on Debian), not measured.
// One-glyph texts "•" and "●" are PLplot's point markers, data rather than text, and are left out.

#include <filesystem>
#include <string>
#include <vector>

namespace fvm::test {

struct TextBox {
  std::string text;
  double x0, y0, x1, y1;  // canvas (viewBox) coordinates, y down, the axis-aligned box of the transformed text
};

struct SvgTextLayout {
  double width = 0, height = 0;  // the canvas: the viewBox (or width and height)
  std::vector<TextBox> boxes;
};

// The width of a character, in units of the font size, at or above DejaVu Sans' advance for most characters: digits
// 0.64 (DejaVu 0.636: at 0.6, "1000" and "1500" written edge to edge pass), capitals 0.76, m, w, M, W 1.0, the rest
// 0.6 (lower-case letters are 0.28 to 0.65, most near 0.6). The extent above and below the baseline likewise.
double CharWidthEm(char32_t c);
inline constexpr double kAscentEm = 0.76, kDescentEm = 0.24;

// Throws std::runtime_error naming the file when it is not an SVG document.
SvgTextLayout ReadSvgTextLayout(const std::filesystem::path& svg);
SvgTextLayout ParseSvgTextLayout(const std::string& svg_text);

// One sentence per problem: two texts whose boxes overlap by more than `tolerance` (canvas units) in both
// directions, or a text that runs more than `tolerance` past the canvas. Empty: the layout is clean.
std::vector<std::string> TextLayoutProblems(const SvgTextLayout& layout, double tolerance = 0.5);

}  // namespace fvm::test
