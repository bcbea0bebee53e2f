// Stations JSON of fvm multilaterate (artefacts/io/multilateration_readings.h): {"stations": [{"name", "x", "y",
// "z"}]}.
#include "artefacts/io/multilateration_readings.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = fvm::fuzz::Scratch().Write("stations.json", fvm::fuzz::Bytes(data, size));
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::artefacts::ReadStations(file); });
  return 0;
}
