// PCD (imaging/io/pcd_file.h): the header, the ascii rows, the binary body and the LZF-compressed body.
#include "imaging/io/pcd_file.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::imaging::ParsePcd(fvm::fuzz::Bytes(data, size), "fuzz.pcd"); });
  return 0;
}
