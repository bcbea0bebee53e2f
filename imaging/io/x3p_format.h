#pragma once
// What the X3P reader (x3p_reader.cc) and writer (x3p_writer.cc) share: the container's fixed entry names, the
// bytes of a point of each data type, and the points as the file holds them.

#include <bit>
#include <cstddef>
#include <vector>

namespace fvm::imaging {

static_assert(std::endian::native == std::endian::little,
              "X3P binary data is little-endian and is copied as it is; add byte swapping for this platform");

inline constexpr const char* kX3pMainXml = "main.xml";
inline constexpr const char* kX3pChecksumFile = "md5checksum.hex";

// The bytes of one point of X3P data type I, L, F or D.
inline std::size_t X3pTypeSize(char data_type) {
  switch (data_type) {
    case 'I':
      return 2;
    case 'L':
    case 'F':
      return 4;
    default:
      return 8;
  }
}

// A surface's values as the file holds them, before Offset and Increment, and its validity bits (empty: all valid).
struct X3pPoints {
  std::vector<double> raw;
  std::vector<bool> valid;
};

}  // namespace fvm::imaging
