// Height-map images (imaging/io/height_map_image.h): TIFF and PNG through OpenImageIO, and fvm's checks after.
#include "imaging/io/height_map_image.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/image_name.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto bytes = fvm::fuzz::Bytes(data, size);
  const auto file = fvm::fuzz::Scratch().Write(fvm::fuzz::ImageName(bytes, "height"), bytes);
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::imaging::ReadHeightMapImage(file); });
  return 0;
}
