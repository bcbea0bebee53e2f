// Keyence VK4 (imaging/io/keyence_vk4.h): the header, the offset table, the measurement conditions, the images.
#include <string>

#include "imaging/io/keyence_vk4.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly(
      [&] { fvm::imaging::ParseKeyenceVk4(std::string(fvm::fuzz::Bytes(data, size)), "fuzz.vk4"); });
  return 0;
}
