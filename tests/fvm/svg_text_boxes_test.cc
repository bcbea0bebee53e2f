// The text-box estimate of tests/fvm/svg_text_boxes.h on hand-written SVG whose boxes are known by hand: anchors,
// PLplot's flipped frames, rotation, the canvas edge, and overlaps that are and are not there.

#include "tests/fvm/svg_text_boxes.h"

#include <gtest/gtest.h>

#include <string>

namespace fvm::test {
namespace {

std::string Svg(const std::string& body) {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"200pt\" height=\"100pt\" viewBox=\"0 0 200 100\">" + body +
         "</svg>";
}

// 5 lower-case characters at font-size 10: 30 wide (0.6 em each), from 7.6 above the baseline to 2.4 below.
TEST(SvgTextBoxes, AnchorsPlaceTheBoxAroundX) {
  const SvgTextLayout layout = ParseSvgTextLayout(Svg(
      "<text x=\"50\" y=\"20\" font-size=\"10\">hello</text>"
      "<text x=\"50\" y=\"40\" font-size=\"10\" text-anchor=\"middle\">hello</text>"
      "<g text-anchor=\"end\"><text x=\"50\" y=\"60\" font-size=\"10\"><tspan>hello</tspan></text></g>"));
  ASSERT_EQ(layout.boxes.size(), 3u);
  EXPECT_DOUBLE_EQ(layout.width, 200);
  EXPECT_DOUBLE_EQ(layout.boxes[0].x0, 50);
  EXPECT_DOUBLE_EQ(layout.boxes[0].x1, 80);
  EXPECT_DOUBLE_EQ(layout.boxes[0].y0, 12.4);
  EXPECT_DOUBLE_EQ(layout.boxes[0].y1, 22.4);
  EXPECT_DOUBLE_EQ(layout.boxes[1].x0, 35);
  EXPECT_DOUBLE_EQ(layout.boxes[1].x1, 65);
  EXPECT_DOUBLE_EQ(layout.boxes[2].x0, 20);
  EXPECT_DOUBLE_EQ(layout.boxes[2].x1, 50);
  EXPECT_EQ(layout.boxes[2].text, "hello");
  EXPECT_TRUE(TextLayoutProblems(layout).empty());
}

// PLplot's svg driver: a page flipped upside down, each text flipped back and moved by its own matrix; "µ" is one
// character (0.6 em), "m" a wide one (1.0 em).
TEST(SvgTextBoxes, FollowsPlplotsFlippedFramesAndRotation) {
  const SvgTextLayout layout = ParseSvgTextLayout(Svg(
      "<g transform=\"matrix(1 0 0 -1 0 100)\">"
      "<text font-size=\"10\" transform=\"matrix(1 0 0 -1 100 70)\" x=\"0\" y=\"0\">µm</text>"
      "<text font-size=\"10\" transform=\"matrix(0 -1 1 0 20 50)\" x=\"0\" y=\"0\" text-anchor=\"middle\">abcd</text>"
      "</g>"));
  ASSERT_EQ(layout.boxes.size(), 2u);
  const TextBox& flat = layout.boxes[0];  // baseline at y = 100 - 70 = 30 on the canvas
  EXPECT_DOUBLE_EQ(flat.x0, 100);
  EXPECT_DOUBLE_EQ(flat.x1, 116);
  EXPECT_NEAR(flat.y0, 22.4, 1e-12);
  EXPECT_NEAR(flat.y1, 32.4, 1e-12);
  // Rotated a quarter turn (reading upwards on the canvas): 24 tall, 10 wide, centred on y = 50.
  const TextBox& turned = layout.boxes[1];
  EXPECT_NEAR(turned.y0, 38, 1e-12);
  EXPECT_NEAR(turned.y1, 62, 1e-12);
  EXPECT_NEAR(turned.x1 - turned.x0, 10, 1e-12);
}

TEST(SvgTextBoxes, FindsOverlapsAndTextPastTheCanvas) {
  // A figure title written over a panel title (both centred on the same line), a label apart from both.
  const SvgTextLayout overlap = ParseSvgTextLayout(Svg(
      "<text x=\"100\" y=\"20\" font-size=\"10\" text-anchor=\"middle\">Volumetric error</text>"
      "<text x=\"110\" y=\"24\" font-size=\"10\" text-anchor=\"middle\">XY view</text>"
      "<text x=\"100\" y=\"80\" font-size=\"10\" text-anchor=\"middle\">x (mm)</text>"));
  const std::vector<std::string> problems = TextLayoutProblems(overlap);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("'Volumetric error'"), std::string::npos) << problems[0];
  EXPECT_NE(problems[0].find("overlaps 'XY view'"), std::string::npos) << problems[0];
  // Lines 10 apart at font-size 10 touch (7.6 + 2.4) but do not overlap.
  EXPECT_TRUE(TextLayoutProblems(ParseSvgTextLayout(
                  Svg("<text x=\"10\" y=\"20\" font-size=\"10\">one</text><text x=\"10\" y=\"30\" font-size=\"10\">two</text>")))
                  .empty());
  // A rotated unit whose top is cut off at the left edge.
  const std::vector<std::string> cut = TextLayoutProblems(ParseSvgTextLayout(
      Svg("<text transform=\"rotate(-90)\" x=\"-50\" y=\"3\" font-size=\"10\" text-anchor=\"middle\">µm</text>")));
  ASSERT_EQ(cut.size(), 1u);
  EXPECT_NE(cut[0].find("runs past the canvas"), std::string::npos) << cut[0];
}

// Tick numbers written edge to edge ("10001500" on an axis): 4 digits at font-size 10 are 25.4 wide in DejaVu Sans,
// so centres 25 apart touch; the estimate (0.64 em a digit) must see them, and not numbers 30 apart.
TEST(SvgTextBoxes, SeesNumbersWrittenEdgeToEdge) {
  const auto ticks = [](int apart) {
    return TextLayoutProblems(ParseSvgTextLayout(Svg(
        "<text x=\"50\" y=\"20\" font-size=\"10\" text-anchor=\"middle\">1000</text><text x=\"" +
        std::to_string(50 + apart) + "\" y=\"20\" font-size=\"10\" text-anchor=\"middle\">1500</text>")));
  };
  EXPECT_EQ(ticks(25).size(), 1u);
  EXPECT_TRUE(ticks(30).empty());
  EXPECT_DOUBLE_EQ(CharWidthEm(U'7'), 0.64);
  EXPECT_DOUBLE_EQ(CharWidthEm(U'W'), 1.0);
}

TEST(SvgTextBoxes, RefusesWhatIsNotAnSvg) {
  EXPECT_THROW(ParseSvgTextLayout("<html></html>"), std::runtime_error);
  EXPECT_THROW(ParseSvgTextLayout("<svg"), std::runtime_error);
  EXPECT_THROW(ReadSvgTextLayout("/nonexistent/plot.svg"), std::runtime_error);
}

}  // namespace
}  // namespace fvm::test
