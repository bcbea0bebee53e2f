#include "fvm/option_parsing.h"

#include <fmt/core.h>

#include <optional>

#include "core/input_error.h"
#include "core/number_text.h"

namespace fvm::cli {
namespace {

// "V,V,V" for three numbers separated by commas, "V" for a list of any length.
std::string FormOf(size_t count, char separator) {
  std::string form = "V";
  for (size_t k = 1; k < count; ++k) form += std::string(1, separator) + "V";
  return form;
}

}  // namespace

std::vector<double> ParseNumbers(std::string_view text, size_t count, const std::string& what, const std::string& example,
                                 const NumberRange& range, char separator) {
  std::vector<double> values;
  size_t start = 0;
  while (true) {
    const size_t end = text.find(separator, start);
    const std::optional<double> v = ParseDouble(text.substr(start, end == std::string_view::npos ? end : end - start));
    if (!v) {
      values.clear();
      break;
    }
    values.push_back(*v);
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  if (values.empty() || (count > 0 && values.size() != count)) {
    const std::string how = count > 0 ? fmt::format("give {} numbers separated by '{}'", count, separator)
                                      : fmt::format("give numbers separated by '{}'", separator);
    throw InputError(fmt::format("{} '{}': {}, e.g. {}", what, text, how, example));
  }
  for (const double v : values) {
    const std::string refusal = range.Refusal(v);
    if (!refusal.empty()) throw InputError(fmt::format("{} '{}': {}", what, text, refusal));
  }
  return values;
}

std::vector<double> ParseNumberList(const std::string& text, const std::string& what, const std::string& example) {
  return ParseNumbers(text, 0, what, example);
}

Eigen::Vector3d ParseVector3(std::string_view text, const std::string& what, const std::string& example,
                             const NumberRange& range) {
  const std::vector<double> v = ParseNumbers(text, 3, what, example, range);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

stage::Pose ParsePose(std::string_view text, const std::string& what) {
  const std::string example = "1100,-1000,600,63,14,35 (X,Y,Z in mm, XYZ Euler angles in deg)";
  const std::vector<double> v = ParseNumbers(text, 6, what, example);
  for (size_t k = 3; k < 6; ++k) {
    const std::string refusal = kAngleDeg.Refusal(v[k]);
    if (!refusal.empty()) throw InputError(fmt::format("{} '{}': angle {}", what, text, refusal));
  }
  return stage::Pose::FromEulerXyzDegrees(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
}

artefacts::Workspace ParseMachine(std::string_view text) {
  const size_t at = text.find('@');
  const std::string example = "2500x1500x1200, optionally with the origin: 2500x1500x1200@0,0,0";
  std::string sizes(text.substr(0, at));
  for (char& c : sizes) c = c == 'X' ? 'x' : c;
  const std::vector<double> size = ParseNumbers(sizes, 3, "--machine travels", example, kTravelMm, 'x');
  artefacts::Workspace ws;
  if (at != std::string_view::npos) ws.min = ParseVector3(text.substr(at + 1), "--machine origin", "2500x1500x1200@0,-750,0");
  for (int k = 0; k < 3; ++k) ws.max[k] = ws.min[k] + size[static_cast<size_t>(k)];
  return ws;
}

CLI::Validator NumbersCheck(size_t count, const std::string& what, const std::string& example, const NumberRange& range,
                            char separator) {
  const std::string form = FormOf(count, separator);
  return ParsesWithin([=](const std::string& t) { ParseNumbers(t, count, what, example, range, separator); }, form, range,
                      count > 0 ? form : "V,...");
}

CLI::Validator PoseCheck(const std::string& what) {
  return ParsesWithin([what](const std::string& t) { ParsePose(t, what); }, "V,V,V,V,V,V", kCoordinateMm, "X,Y,Z,A,B,C");
}

CLI::Validator MachineCheck() {
  return ParsesWithin([](const std::string& t) { ParseMachine(t); }, "VxVxV", kTravelMm, "LXxLYxLZ[@X0,Y0,Z0]");
}

}  // namespace fvm::cli
