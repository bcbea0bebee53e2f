// Calibration JSON (stage/io/calibration_file.h ReadCalibration), as fvm correct reads a hand-edited file.
#include "stage/io/calibration_file.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = fvm::fuzz::Scratch().Write("calibration.json", fvm::fuzz::Bytes(data, size));
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::stage::ReadCalibration(file); });
  return 0;
}
