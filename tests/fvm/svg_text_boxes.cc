// Text boxes of an SVG picture (see svg_text_boxes.h): pugixml reads the document, each <text> gets the product of
// the transforms above it, and its box (anchor, baseline, font size, character count) goes through that product.

#include "tests/fvm/svg_text_boxes.h"

#include <fmt/format.h>
#include <pugixml.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace fvm::test {
namespace {

// x' = a x + c y + e, y' = b x + d y + f (the SVG matrix(a b c d e f)).
struct Affine {
  double a = 1, b = 0, c = 0, d = 1, e = 0, f = 0;
  Affine Then(const Affine& inner) const {  // this * inner: inner applies first
    return {a * inner.a + c * inner.b, b * inner.a + d * inner.b, a * inner.c + c * inner.d,
            b * inner.c + d * inner.d, a * inner.e + c * inner.f + e, b * inner.e + d * inner.f + f};
  }
  std::array<double, 2> Apply(double x, double y) const { return {a * x + c * y + e, b * x + d * y + f}; }
};

// The numbers of one transform function, with commas and spaces as separators.
std::vector<double> Numbers(std::string_view text) {
  std::vector<double> out;
  std::string s(text);
  std::replace(s.begin(), s.end(), ',', ' ');
  std::istringstream in(s);
  for (double v; in >> v;) out.push_back(v);
  return out;
}

// An SVG transform list: matrix, translate, scale, rotate, skewX, skewY, applied right to left.
Affine ParseTransform(std::string_view list) {
  Affine total;
  std::size_t pos = 0;
  while (true) {
    const std::size_t open = list.find('(', pos);
    if (open == std::string_view::npos) break;
    const std::size_t close = list.find(')', open);
    if (close == std::string_view::npos) throw std::runtime_error(fmt::format("unclosed transform '{}'", list));
    std::string name(list.substr(pos, open - pos));
    std::erase_if(name, [](char ch) { return ch == ' ' || ch == ',' || ch == '\n' || ch == '\t'; });
    const std::vector<double> v = Numbers(list.substr(open + 1, close - open - 1));
    const auto arg = [&](std::size_t i, double fallback) { return i < v.size() ? v[i] : fallback; };
    Affine t;
    if (name == "matrix" && v.size() == 6) {
      t = {v[0], v[1], v[2], v[3], v[4], v[5]};
    } else if (name == "translate") {
      t.e = arg(0, 0), t.f = arg(1, 0);
    } else if (name == "scale") {
      t.a = arg(0, 1), t.d = arg(1, t.a);
    } else if (name == "rotate") {
      const double r = arg(0, 0) * std::numbers::pi / 180, cx = arg(1, 0), cy = arg(2, 0);
      const Affine rotation{std::cos(r), std::sin(r), -std::sin(r), std::cos(r), 0, 0};
      t = Affine{1, 0, 0, 1, cx, cy}.Then(rotation).Then(Affine{1, 0, 0, 1, -cx, -cy});
    } else if (name == "skewX") {
      t.c = std::tan(arg(0, 0) * std::numbers::pi / 180);
    } else if (name == "skewY") {
      t.b = std::tan(arg(0, 0) * std::numbers::pi / 180);
    } else {
      throw std::runtime_error(fmt::format("unknown transform '{}'", name));
    }
    total = total.Then(t);
    pos = close + 1;
  }
  return total;
}

double Length(const char* text, double fallback) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  return end == text ? fallback : v;  // "1000pt": the number; units do not matter against the viewBox
}

// The width of UTF-8 text in units of the font size. Continuation bytes add nothing; a character outside ASCII counts
// as 0.6 ("µ", "±", "×" are 0.64, 0.84 and 0.84 in DejaVu Sans: close to the rest, within the conservative digits).
double WidthEm(std::string_view utf8) {
  double width = 0;
  for (const char ch : utf8) {
    const auto byte = static_cast<unsigned char>(ch);
    if ((byte & 0xC0) == 0x80) continue;
    width += CharWidthEm(byte < 0x80 ? static_cast<char32_t>(byte) : U'\u00B5');
  }
  return width;
}

// An attribute of the node or the nearest ancestor that has it (font-size and text-anchor are inherited).
std::string Inherited(pugi::xml_node node, const char* name, const char* fallback) {
  for (; node; node = node.parent()) {
    if (const pugi::xml_attribute a = node.attribute(name)) return a.value();
  }
  return fallback;
}

void CollectTexts(pugi::xml_node node, const Affine& above, SvgTextLayout& layout) {
  for (pugi::xml_node child : node.children()) {
    if (child.type() != pugi::node_element) continue;
    const std::string_view name = child.name();
    if (name == "defs" || name == "clipPath" || name == "mask" || name == "symbol") continue;
    const Affine here = above.Then(ParseTransform(child.attribute("transform").value()));
    if (name != "text") {
      CollectTexts(child, here, layout);
      continue;
    }
    // The text's characters, each at its own font size (a <tspan> may set one); PLplot writes one <tspan> per text.
    double width = 0, font_size = 0;
    std::string text;
    for (const pugi::xpath_node& hit : child.select_nodes(".//text()")) {
      const pugi::xml_node part = hit.node();
      const std::string_view chars = part.value();
      const double size = Length(Inherited(part.parent(), "font-size", "16").c_str(), 16);
      width += size * WidthEm(chars);
      font_size = std::max(font_size, size);
      text += chars;
    }
    if (text.find_first_not_of(" \t\n") == std::string::npos) continue;
    // PLplot draws point markers (plpoin, plstring) as one-glyph texts: they are data, which may overlap.
    if (text == "•" || text == "●") continue;
    const double x = child.attribute("x").as_double(0), y = child.attribute("y").as_double(0);
    const std::string anchor = Inherited(child, "text-anchor", "start");
    const double left = anchor == "middle" ? x - width / 2 : anchor == "end" ? x - width : x;
    TextBox box{text, 1e300, 1e300, -1e300, -1e300};
    for (const double cx : {left, left + width}) {
      for (const double cy : {y - kAscentEm * font_size, y + kDescentEm * font_size}) {
        const auto [px, py] = here.Apply(cx, cy);
        box.x0 = std::min(box.x0, px), box.x1 = std::max(box.x1, px);
        box.y0 = std::min(box.y0, py), box.y1 = std::max(box.y1, py);
      }
    }
    layout.boxes.push_back(box);
  }
}

std::string Describe(const TextBox& b) {
  return fmt::format("'{}' [{:.0f}..{:.0f} x {:.0f}..{:.0f}]", b.text, b.x0, b.x1, b.y0, b.y1);
}

}  // namespace

double CharWidthEm(char32_t c) {
  if (c >= U'0' && c <= U'9') return 0.64;
  if (c == U'm' || c == U'w' || c == U'M' || c == U'W') return 1.0;
  if (c >= U'A' && c <= U'Z') return 0.76;
  return 0.6;
}

SvgTextLayout ParseSvgTextLayout(const std::string& svg_text) {
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_string(svg_text.c_str(), pugi::parse_default | pugi::parse_ws_pcdata);
  if (!parsed) throw std::runtime_error(fmt::format("not XML: {} at offset {}", parsed.description(), parsed.offset));
  const pugi::xml_node svg = doc.child("svg");
  if (!svg) throw std::runtime_error("no <svg> root element");
  SvgTextLayout layout;
  Affine root;
  const std::vector<double> view_box = Numbers(svg.attribute("viewBox").value());
  if (view_box.size() == 4) {
    layout.width = view_box[2], layout.height = view_box[3];
    root = Affine{1, 0, 0, 1, -view_box[0], -view_box[1]};
  } else {
    layout.width = Length(svg.attribute("width").value(), 0), layout.height = Length(svg.attribute("height").value(), 0);
  }
  if (!(layout.width > 0 && layout.height > 0)) throw std::runtime_error("the <svg> element has no size");
  CollectTexts(svg, root, layout);
  return layout;
}

SvgTextLayout ReadSvgTextLayout(const std::filesystem::path& svg) {
  pugi::xml_document doc;
  std::ifstream in(svg, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw std::runtime_error(fmt::format("{}: cannot be read", svg.string()));
  try {
    return ParseSvgTextLayout(text.str());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(fmt::format("{}: {}", svg.string(), e.what()));
  }
}

std::vector<std::string> TextLayoutProblems(const SvgTextLayout& layout, double tolerance) {
  std::vector<std::string> problems;
  const std::vector<TextBox>& boxes = layout.boxes;
  for (const TextBox& b : boxes) {
    if (b.x0 < -tolerance || b.y0 < -tolerance || b.x1 > layout.width + tolerance || b.y1 > layout.height + tolerance) {
      problems.push_back(fmt::format("{} runs past the canvas {:g} x {:g}", Describe(b), layout.width, layout.height));
    }
  }
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    for (std::size_t j = i + 1; j < boxes.size(); ++j) {
      const TextBox &p = boxes[i], &q = boxes[j];
      const double dx = std::min(p.x1, q.x1) - std::max(p.x0, q.x0), dy = std::min(p.y1, q.y1) - std::max(p.y0, q.y0);
      if (dx > tolerance && dy > tolerance) problems.push_back(fmt::format("{} overlaps {}", Describe(p), Describe(q)));
    }
  }
  return problems;
}

}  // namespace fvm::test
