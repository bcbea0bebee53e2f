// Laser-tracker readings CSV (artefacts/io/tracker_readings.h): comments, id,x,y,z with xt,yt,zt or
// range,azimuth,elevation, the optional approach column, rows.
#include "artefacts/io/tracker_readings.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = fvm::fuzz::Scratch().Write("readings.csv", fvm::fuzz::Bytes(data, size));
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::artefacts::ReadTrackerReadings(file); });
  return 0;
}
