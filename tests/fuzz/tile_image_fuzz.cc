// Tile images (imaging/io/tile_image.h): TIFF and PNG through OpenImageIO, grey conversion and pixel checks.
#include "imaging/io/tile_image.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/image_name.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto bytes = fvm::fuzz::Bytes(data, size);
  const auto file = fvm::fuzz::Scratch().Write(fvm::fuzz::ImageName(bytes, "tile"), bytes);
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::imaging::ReadTileImage(file); });
  return 0;
}
