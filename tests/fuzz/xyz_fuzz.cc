// XYZ/CSV point text (imaging/io/point_cloud_io.h ParseXyz): separators, header names, the grid comment.
#include <string>

#include "imaging/io/point_cloud_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::imaging::ParseXyz(fvm::fuzz::Bytes(data, size), "fuzz.xyz"); });
  return 0;
}
