// X3P (imaging/io/x3p.h): the zip container, main.xml, the MD5 file and the binary or inline data.
#include <string>

#include "imaging/io/x3p.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseX3p(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.x3p"); });
  return 0;
}
