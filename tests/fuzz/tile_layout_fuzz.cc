// Tile layout CSV (imaging/io/tile_layout.h) or Fiji tile configuration (fiji_tile_configuration.h, the seed
// fiji.txt), and the completeness check fvm stitch runs on it next.
#include "imaging/io/tile_layout.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = fvm::fuzz::Scratch().Write("layout.csv", fvm::fuzz::Bytes(data, size));
  fvm::fuzz::ReadExpectingInputErrorOnly([&] {
    const fvm::imaging::TileLayout layout = fvm::imaging::ReadTileLayout(file);
    fvm::imaging::CheckLayoutForStitching(layout);
  });
  return 0;
}
