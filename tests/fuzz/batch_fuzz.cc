// batch.json of a batch directory (artefacts/io/batch.h ReadBatch). The directory holds two valid placements,
// written once, so that every input reaches the roles: identify, validate, lens.
#include <filesystem>

#include "artefacts/io/batch.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

std::filesystem::path BatchDir() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path batch = fvm::fuzz::Scratch().path() / "batch";
    std::filesystem::create_directories(batch);
    const char* const centres = "id,x,y,z\n1,0,0,0\n2,10,0,0\n3,0,10,0.5\n";
    for (const char* placement : {"a", "b"}) {
      fvm::fuzz::Scratch().Write(std::string("batch/") + placement + ".stitched.csv", centres);
      fvm::fuzz::Scratch().Write(std::string("batch/") + placement + ".free.csv", centres);
    }
    return batch;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path dir = BatchDir();
  fvm::fuzz::Scratch().Write("batch/batch.json", fvm::fuzz::Bytes(data, size));
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::artefacts::ReadBatch(dir); });
  return 0;
}
