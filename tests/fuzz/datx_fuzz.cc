// Zygo DATX (imaging/io/zygo_datx.h): any bytes through HDF5 (the plugin) and the reader's interpretation.
#include <string>

#include "imaging/io/zygo_datx.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseZygoDatx(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.datx"); });
  return 0;
}
