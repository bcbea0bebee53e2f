// Multilateration readings CSV (artefacts/io/multilateration_readings.h): comments, id,station,range with the
// optional azimuth,elevation and x,y,z columns, rows; and the nominal points (id,x,y,z) read for --nominal.
#include "artefacts/io/multilateration_readings.h"
#include "artefacts/io/point_list.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = fvm::fuzz::Scratch().Write("readings.csv", fvm::fuzz::Bytes(data, size));
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::artefacts::ReadMultilaterationReadings(file); });
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::artefacts::ReadPointList(file); });
  return 0;
}
