// ISO 25178-71 SDF (imaging/io/sdf.h): the ASCII header and data, and the binary header and values.
#include <string>

#include "imaging/io/sdf.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseSdf(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.sdf"); });
  return 0;
}
