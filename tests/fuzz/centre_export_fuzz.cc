// Centre export CSV (artefacts/io/centre_export.h): comments, the id,x,y,z header, optional columns, rows.
#include "artefacts/io/centre_export.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = fvm::fuzz::Scratch().Write("centres.csv", fvm::fuzz::Bytes(data, size));
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::artefacts::ReadCentreExport(file); });
  return 0;
}
