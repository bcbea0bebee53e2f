// The option layer every command declares its numeric options with (fvm/option_ranges.h, fvm/option_parsing.h):
// any text given to an option is either refused with a message, or read as finite numbers inside the option's
// span; and a command line of any words parses or stops with a CLI11 usage error, nothing else. A text that a
// check accepts but whose numbers fall outside the span is a finding (abort), as is any crash or other exception.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/number_text.h"
#include "fvm/option_parsing.h"
#include "fvm/option_ranges.h"
#include "imaging/tile_plan.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

using namespace fvm::cli;

bool Accepts(const CLI::Validator& check, const std::string& text) {
  std::string copy = text;
  return check(copy).empty();
}

void Require(bool holds) {
  if (!holds) std::abort();
}

bool Inside(double v, const NumberRange& r) { return std::isfinite(v) && v >= r.min && v <= r.max; }

// Every check on one text: what it accepts reads back inside its span.
void CheckOneValue(const std::string& text) {
  if (Accepts(Within(kTravelMm), text)) Require(Inside(*fvm::ParseDouble(text), kTravelMm));
  const NumberRange runs{1, 100000, "", true};
  if (Accepts(Within(runs), text)) {
    const double v = *fvm::ParseDouble(text);
    Require(Inside(v, runs) && v == std::floor(v));
  }
  if (Accepts(NumbersCheck(3, "--tool", "0,0,100"), text)) {
    const Eigen::Vector3d v = ParseVector3(text, "--tool", "0,0,100");
    for (int k = 0; k < 3; ++k) Require(Inside(v[k], kCoordinateMm));
  }
  if (Accepts(NumbersCheck(0, "--heights", "-50,-40"), text)) {
    for (const double v : ParseNumberList(text, "--heights", "-50,-40")) Require(Inside(v, kCoordinateMm));
  }
  if (Accepts(PoseCheck("--pose"), text)) {
    const fvm::stage::Pose p = ParsePose(text, "--pose");
    Require(p.translation.allFinite() && p.rotation.allFinite());
  }
  if (Accepts(MachineCheck(), text)) {
    const fvm::artefacts::Workspace ws = ParseMachine(text);
    for (int k = 0; k < 3; ++k) Require(Inside(ws.max[k] - ws.min[k], {0.9e-3, 1.1e5, "mm"}) && std::isfinite(ws.min[k]));
  }
  if (Accepts(OverlapCheck("--overlap"), text)) {
    const double f = fvm::imaging::ParseOverlap(text, "--overlap");
    Require(f >= 0.01 && f <= 0.99);
  }
}

// A command line of the words in `text` (split at blanks) through options declared as the commands declare them.
void ParseCommandLine(const std::string& text) {
  CLI::App app{"fuzz", "fvm"};
  double k = 2.0, pixel = 0.0;
  int runs = 1000;
  std::vector<std::string> tools;
  std::string machine, pose, overlap;
  std::vector<double> from;
  app.add_option("--k", k)->check(Within(0.5, 10.0));
  app.add_option("--pixel-mm", pixel)->check(Within(kPixelMm));
  app.add_option("--runs", runs)->check(Count(1, 100000));
  app.add_option("--tool", tools)->check(NumbersCheck(3, "--tool", "0,0,100"));
  app.add_option("--machine", machine)->check(MachineCheck());
  app.add_option("--pose", pose)->check(PoseCheck("--pose"));
  app.add_option("--overlap", overlap)->check(OverlapCheck("--overlap"));
  app.add_option("--from", from)->check(Within(kCoordinateMm))->delimiter(',')->expected(3);
  RefuseNonFinite(app);
  std::vector<std::string> words;
  std::string word;
  for (const char c : text) {
    if (c == ' ' || c == '\n' || c == '\t' || c == '\0') {
      if (!word.empty()) words.push_back(word);
      word.clear();
    } else {
      word += c;
    }
  }
  if (!word.empty()) words.push_back(word);
  std::reverse(words.begin(), words.end());  // CLI11 takes the arguments last first
  try {
    app.parse(words);
  } catch (const CLI::ParseError&) {
    return;  // a usage error: exit 2 with its message
  }
  Require(k >= 0.5 && k <= 10.0 && runs >= 1 && runs <= 100000 && (pixel == 0.0 || Inside(pixel, kPixelMm)));
  for (const double v : from) Require(Inside(v, kCoordinateMm));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 4096) return 0;
  const std::string text(fvm::fuzz::Bytes(data, size));
  CheckOneValue(text);
  ParseCommandLine(text);
  return 0;
}
