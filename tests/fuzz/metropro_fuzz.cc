// Zygo MetroPro DAT (imaging/io/metropro_dat.h): the big-endian header, the intensity and the phase.
#include <string>

#include "imaging/io/metropro_dat.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseMetroProDat(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.metropro"); });
  return 0;
}
