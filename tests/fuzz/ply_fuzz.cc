// PLY (imaging/io/ply_file.h): the header, ascii and binary bodies, lists, PCL's range_grid.
#include "imaging/io/ply_file.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::imaging::ParsePly(fvm::fuzz::Bytes(data, size), "fuzz.ply"); });
  return 0;
}
