// Focus stack list CSV (imaging/io/focus_stack_io.h ReadFocusStackList): file,z_mm rows.
#include "imaging/io/focus_stack_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = fvm::fuzz::Scratch().Write("stack.csv", fvm::fuzz::Bytes(data, size));
  fvm::fuzz::ReadExpectingInputErrorOnly([&] { fvm::imaging::ReadFocusStackList(file); });
  return 0;
}
