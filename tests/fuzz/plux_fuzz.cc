// Sensofar PLUx (imaging/io/sensofar_plux.h): the zip container, index.xml and the layer it names.
#include <string>

#include "imaging/io/sensofar_plux.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseSensofarPlux(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.plux"); });
  return 0;
}
