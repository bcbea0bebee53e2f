// AL3D (imaging/io/al3d.h): the tag header and the height and texture blocks it points to.
#include <string>

#include "imaging/io/al3d.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseAl3d(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.al3d"); });
  return 0;
}
