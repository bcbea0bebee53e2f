// Olympus LEXT (imaging/io/olympus_lext.h): the TIFF's page chain, page 0's XML, the named pages (through the
// image plugin, like the image readers).
#include "imaging/io/olympus_lext.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto bytes = fvm::fuzz::Bytes(data, size);
  const auto file = fvm::fuzz::Scratch().Write("fuzz.lext", bytes);
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::imaging::ReadOlympusLext(file); });
  return 0;
}
