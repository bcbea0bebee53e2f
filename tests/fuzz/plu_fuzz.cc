// Sensofar PLU (imaging/io/sensofar_plu.h): the header, the heights and the colour image after them.
#include <string>

#include "imaging/io/sensofar_plu.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseSensofarPlu(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.plu"); });
  return 0;
}
