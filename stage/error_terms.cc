#include "stage/error_terms.h"

#include <algorithm>
#include <array>
#include <stdexcept>

namespace fvm::stage {
namespace {

constexpr ErrorKind T = ErrorKind::kTranslation;
constexpr ErrorKind R = ErrorKind::kRotation;
constexpr ErrorKind W = ErrorKind::kSquareness;
constexpr Axis X = Axis::kX;
constexpr Axis Y = Axis::kY;
constexpr Axis Z = Axis::kZ;

constexpr std::array<ErrorTerm, kNumErrorTerms> kTerms{{
    {0, T, X, 0, "xTx", "EXX"},  {1, T, X, 1, "xTy", "EYX"},  {2, T, X, 2, "xTz", "EZX"},
    {3, R, X, 0, "xRx", "EAX"},  {4, R, X, 1, "xRy", "EBX"},  {5, R, X, 2, "xRz", "ECX"},
    {6, T, Y, 0, "yTx", "EXY"},  {7, T, Y, 1, "yTy", "EYY"},  {8, T, Y, 2, "yTz", "EZY"},
    {9, R, Y, 0, "yRx", "EAY"},  {10, R, Y, 1, "yRy", "EBY"}, {11, R, Y, 2, "yRz", "ECY"},
    {12, T, Z, 0, "zTx", "EXZ"}, {13, T, Z, 1, "zTy", "EYZ"}, {14, T, Z, 2, "zTz", "EZZ"},
    {15, R, Z, 0, "zRx", "EAZ"}, {16, R, Z, 1, "zRy", "EBZ"}, {17, R, Z, 2, "zRz", "ECZ"},
    {18, W, X, 1, "xWy", "EC0Y"}, {19, W, X, 2, "xWz", "EB0Z"}, {20, W, Y, 2, "yWz", "EA0Z"},
}};

}  // namespace

char AxisLetter(Axis axis) { return "xyz"[static_cast<int>(axis)]; }

const ErrorTerm& GetErrorTerm(int index) {
  if (index < 0 || index >= kNumErrorTerms) throw std::out_of_range("error term index out of range");
  return kTerms[static_cast<size_t>(index)];
}

int TranslationTerm(Axis axis, int component) { return static_cast<int>(axis) * 6 + component; }
int RotationTerm(Axis axis, int component) { return static_cast<int>(axis) * 6 + 3 + component; }

int SquarenessTerm(Axis first, Axis second) {
  const int a = std::min(static_cast<int>(first), static_cast<int>(second));
  const int b = std::max(static_cast<int>(first), static_cast<int>(second));
  if (a == b) throw std::invalid_argument("squareness needs two different axes");
  return kFirstSquarenessTerm + a + b - 1;  // xy -> 18, xz -> 19, yz -> 20
}

std::optional<int> FindErrorTerm(std::string_view name) {
  for (const ErrorTerm& term : kTerms) {
    if (term.vdi == name || term.iso == name) return term.index;
  }
  return std::nullopt;
}

}  // namespace fvm::stage
