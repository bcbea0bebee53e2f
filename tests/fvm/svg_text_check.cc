// svg_text_check FILE.svg...: prints every text of the pictures that overlaps another text or runs past the canvas
// (tests/fvm/svg_text_boxes.h says what the estimate can and cannot see); exit 1 when there is one, 2 when a file
// is not an SVG document. The report pictures test (report_pictures_cli_test.cmake) runs it on every report.

#include <fmt/format.h>

#include <exception>

#include "tests/fvm/svg_text_boxes.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    fmt::print(stderr, "usage: svg_text_check FILE.svg...\n");
    return 2;
  }
  int status = 0;
  for (int i = 1; i < argc; ++i) {
    try {
      const fvm::test::SvgTextLayout layout = fvm::test::ReadSvgTextLayout(argv[i]);
      const std::vector<std::string> problems = fvm::test::TextLayoutProblems(layout);
      for (const std::string& p : problems) fmt::print("{}: {}\n", argv[i], p);
      if (layout.boxes.empty()) fmt::print("{}: no text at all\n", argv[i]);
      if (!problems.empty() || layout.boxes.empty()) status = std::max(status, 1);
    } catch (const std::exception& e) {
      fmt::print(stderr, "{}\n", e.what());
      status = 2;
    }
  }
  return status;
}
