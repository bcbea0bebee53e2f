#pragma once
// The 21 geometric error terms of a three-axis machine, named after [VDI 2617-3].
//
// Per axis k in {x, y, z}: kTx, kTy, kTz (translation: positioning along k, straightness across it) and
// kRx, kRy, kRz (rotation: roll, pitch, yaw about x, y, z), each a function of the k coordinate; plus the three
// squareness terms xWy, xWz, yWz. [ISO 230-1] aliases (EXX, EYX, ..., EC0Y) are accepted as names too.

#include <optional>
#include <string_view>

namespace fvm::stage {

enum class Axis : int { kX = 0, kY = 1, kZ = 2 };

inline constexpr int kNumErrorTerms = 21;
inline constexpr int kFirstSquarenessTerm = 18;

enum class ErrorKind { kTranslation, kRotation, kSquareness };

struct ErrorTerm {
  int index = 0;           // 0..20: axis * 6 + (0..2 translation, 3..5 rotation); 18..20 squareness
  ErrorKind kind = ErrorKind::kTranslation;
  Axis axis = Axis::kX;    // T, R: the moving axis; W: the first axis of the pair (x of xWy)
  int component = 0;       // T, R: direction 0..2 (x, y, z); W: the second axis of the pair (y of xWy)
  std::string_view vdi;    // "xTy"
  std::string_view iso;    // "EYX"
};

char AxisLetter(Axis axis);
const ErrorTerm& GetErrorTerm(int index);
int TranslationTerm(Axis axis, int component);
int RotationTerm(Axis axis, int component);
int SquarenessTerm(Axis first, Axis second);  // order-free: (y, x) is xWy
// Finds a term by VDI name ("xTy") or ISO 230-1 alias ("EYX", "EC0Y"); nullopt when unknown.
std::optional<int> FindErrorTerm(std::string_view name);

}  // namespace fvm::stage
