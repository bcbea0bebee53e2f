#pragma once
// What the surface and point-cloud readers share: the failure that names the file, the limit of what a map or a
// cloud can hold, and reading a little-endian number from raw bytes.

#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include "core/input_error.h"

namespace fvm::imaging {

// HeightMap and PointCloud sizes are ints; beyond this a map would not fit in memory anyway.
inline constexpr std::uint64_t kMaxPoints = std::numeric_limits<int>::max();
inline constexpr double kMmPerMetre = 1000.0;

// Throws InputError "<where>: <problem>": `where` names the file (and the line or record).
[[noreturn]] inline void FailReading(const std::string& where, const std::string& problem) {
  throw InputError(where + ": " + problem);
}

// A T stored at p in the machine's byte order (every format read here is little-endian, as x86 and ARM are).
template <typename T>
T LoadBytes(const char* p) {
  T value;
  std::memcpy(&value, p, sizeof value);
  return value;
}

}  // namespace fvm::imaging
