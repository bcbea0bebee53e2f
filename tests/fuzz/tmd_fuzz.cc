// GelSight TMD (imaging/io/gelsight_tmd.h): the signature, the comment, the header and the heights.
#include <string>

#include "imaging/io/gelsight_tmd.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseGelSightTmd(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.tmd"); });
  return 0;
}
