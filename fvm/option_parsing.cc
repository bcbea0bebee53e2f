#include "fvm/option_parsing.h"

#include <sstream>

#include <fmt/core.h>

#include <cmath>
#include <optional>

#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::cli {

std::vector<double> ParseNumbers(std::string_view text, size_t count, const std::string& what, const std::string& example) {
  std::vector<double> values;
  size_t start = 0;
  while (true) {
    const size_t end = text.find(',', start);
    const std::optional<double> v = ParseDouble(text.substr(start, end == std::string_view::npos ? end : end - start));
    if (!v || !std::isfinite(*v)) {
      values.clear();
      break;
    }
    values.push_back(*v);
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  if (values.size() != count) {
    throw InputError(fmt::format("{} '{}': give {} numbers separated by commas, e.g. {}", what, text, count, example));
  }
  return values;
}

std::vector<double> ParseNumberList(const std::string& text, const std::string& what, const std::string& example) {
  std::vector<double> out;
  std::stringstream list(text);
  for (std::string item; std::getline(list, item, ',');) out.push_back(ParseNumbers(item, 1, what, example)[0]);
  return out;
}

Eigen::Vector3d ParseVector3(std::string_view text, const std::string& what, const std::string& example) {
  const std::vector<double> v = ParseNumbers(text, 3, what, example);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

stage::Pose ParsePose(std::string_view text, const std::string& what) {
  const std::vector<double> v = ParseNumbers(text, 6, what, "1100,-1000,600,63,14,35 (X,Y,Z in mm, XYZ Euler angles in deg)");
  return stage::Pose::FromEulerXyzDegrees(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
}

artefacts::Workspace ParseMachine(std::string_view text) {
  const size_t at = text.find('@');
  std::string sizes(text.substr(0, at));
  for (char& c : sizes) c = c == 'x' || c == 'X' ? ',' : c;
  std::vector<double> size;
  try {
    size = ParseNumbers(sizes, 3, "--machine", "");
  } catch (const InputError&) {
    throw InputError(fmt::format("--machine '{}': give the three travels LXxLYxLZ in mm, e.g. 2500x1500x1200, "
                                 "optionally with the origin: 2500x1500x1200@0,0,0",
                                 text));
  }
  artefacts::Workspace ws;
  if (at != std::string_view::npos) {
    ws.min = ParseVector3(text.substr(at + 1), "--machine origin", "2500x1500x1200@0,-750,0");
  }
  for (int k = 0; k < 3; ++k) {
    if (!(size[static_cast<size_t>(k)] > 0.0) || size[static_cast<size_t>(k)] > 100'000.0) {
      throw InputError(fmt::format("--machine '{}': the {} travel must be > 0 and at most 100000 mm", text, "xyz"[k]));
    }
    ws.max[k] = ws.min[k] + size[static_cast<size_t>(k)];
  }
  return ws;
}

}  // namespace fvm::cli
