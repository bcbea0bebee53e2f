// Wyko OPD (imaging/io/wyko_opd.h): the directory, its blocks and the arrays.
#include <string>

#include "imaging/io/wyko_opd.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseWykoOpd(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.opd"); });
  return 0;
}
