// Digital Surf SUR (imaging/io/digital_surf_sur.h): the header, plain and zlib-compressed counts.
#include <string>

#include "imaging/io/digital_surf_sur.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseDigitalSurfSur(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.sur"); });
  return 0;
}
