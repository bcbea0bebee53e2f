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

// `value` appended to `bytes` in the machine's byte order: the writers' side of LoadBytes.
template <typename T>
void AppendBytes(std::string& bytes, T value) {
  char buffer[sizeof(T)];
  std::memcpy(buffer, &value, sizeof value);
  bytes.append(buffer, sizeof buffer);
}

// Refuses, naming the file, a grid of no point or more than a map can hold: "<file>: <says> C x R points, not a grid
// fvm can hold; <remedy>" (`says`: "says", "the data block says").
inline void RequireGridSize(const std::string& name, const std::string& says, std::uint64_t cols, std::uint64_t rows,
                            const std::string& remedy) {
  if (cols < 1 || rows < 1 || cols * rows > kMaxPoints) {
    FailReading(name, says + " " + std::to_string(cols) + " x " + std::to_string(rows) +
                          " points, not a grid fvm can hold; " + remedy);
  }
}

// A T stored big-endian at p (Zygo MetroPro headers and data).
template <typename T>
T LoadBigEndian(const char* p) {
  char swapped[sizeof(T)];
  for (std::size_t i = 0; i < sizeof(T); ++i) swapped[i] = p[sizeof(T) - 1 - i];
  return LoadBytes<T>(swapped);
}

// A fixed-size text field: up to its first NUL, blanks trimmed.
inline std::string FixedText(const char* p, std::size_t size) {
  std::size_t n = 0;
  while (n < size && p[n] != '\0') ++n;
  std::size_t begin = 0;
  while (begin < n && (p[begin] == ' ' || p[begin] == '\t')) ++begin;
  while (n > begin && (p[n - 1] == ' ' || p[n - 1] == '\t' || p[n - 1] == '\r' || p[n - 1] == '\n')) --n;
  return std::string(p + begin, n - begin);
}

}  // namespace fvm::imaging
