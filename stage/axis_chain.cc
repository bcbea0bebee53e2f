#include "stage/axis_chain.h"

#include <algorithm>
#include <stdexcept>

namespace fvm::stage {
namespace {

std::optional<Axis> AxisFromLetter(char c) {
  switch (c) {
    case 'X': case 'x': return Axis::kX;
    case 'Y': case 'y': return Axis::kY;
    case 'Z': case 'z': return Axis::kZ;
    default: return std::nullopt;
  }
}

}  // namespace

AxisChain AxisChain::Parse(std::string_view code, SquarenessCarrier carrier) {
  const std::string text(code);
  const auto fail = [&](const std::string& why) {
    throw std::invalid_argument("axis chain '" + text + "': " + why +
                                " (write the three axes X, Y, Z and one F, e.g. YXFZ, XFYZ, FXYZ)");
  };
  AxisChain chain;
  chain.code = text;
  bool seen_f = false;
  std::array<bool, 3> seen{};
  for (char c : code) {
    if (c == 'F' || c == 'f') {
      if (seen_f) fail("F appears twice");
      seen_f = true;
      continue;
    }
    const std::optional<Axis> axis = AxisFromLetter(c);
    if (!axis) fail(std::string("unknown letter '") + c + "'");
    if (seen[static_cast<size_t>(*axis)]) fail(std::string("axis ") + c + " appears twice");
    seen[static_cast<size_t>(*axis)] = true;
    (seen_f ? chain.tool_axes : chain.part_axes).push_back(*axis);
  }
  if (!seen_f) fail("no F (fixed frame)");
  if (!(seen[0] && seen[1] && seen[2])) fail("an axis is missing");

  // Order along the chain from the part to the tool: the part side read from the part inward, then the tool
  // side from the frame outward.
  std::vector<Axis> from_part(chain.part_axes.rbegin(), chain.part_axes.rend());
  from_part.insert(from_part.end(), chain.tool_axes.begin(), chain.tool_axes.end());
  const auto position = [&](Axis a) { return std::find(from_part.begin(), from_part.end(), a) - from_part.begin(); };
  for (int w = 0; w < 3; ++w) {
    const ErrorTerm& term = GetErrorTerm(kFirstSquarenessTerm + w);
    const Axis a = term.axis;
    const Axis b = static_cast<Axis>(term.component);
    const bool a_nearer_part = position(a) < position(b);
    chain.squareness_carrier[static_cast<size_t>(w)] =
        (carrier == SquarenessCarrier::kPartEnd) == a_nearer_part ? a : b;
  }
  return chain;
}

AxisChain AxisChain::FvmStage() { return Parse("YXFZ", SquarenessCarrier::kPartEnd); }

Axis AxisChain::ArgumentAxis(int term) const {
  const ErrorTerm& info = GetErrorTerm(term);
  if (info.kind == ErrorKind::kSquareness) return squareness_carrier[static_cast<size_t>(term - kFirstSquarenessTerm)];
  return info.axis;
}

bool AxisChain::IsPartSide(Axis axis) const {
  return std::find(part_axes.begin(), part_axes.end(), axis) != part_axes.end();
}

}  // namespace fvm::stage
