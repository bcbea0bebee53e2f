// NMS height images (imaging/io/nms_file.h): the header and the counts.
#include <string>

#include "imaging/io/nms_file.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseNms(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.nms"); });
  return 0;
}
