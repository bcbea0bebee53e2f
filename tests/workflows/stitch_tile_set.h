#pragma once
// What the stitching workflow tests share: a scratch directory of their own, and the 3 x 3 set of 8-bit tiles (256 px,
// 20 % overlap, 1.5 px of stage error; seed 4) that `fvm tiles synthesize` writes there.

#include <fmt/core.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "workflows/tiles_synthesize.h"

namespace fvm::workflows {

// A fresh (emptied) scratch directory for one test of `suite`, named per process.
inline std::filesystem::path StitchScratch(const std::string& suite, const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / fmt::format("fvm_{}_{}_{}", suite, name, ::getpid());
  std::filesystem::remove_all(dir);
  return dir;
}

// The options that write the shared 8-bit set into `dir`.
inline TilesSynthesizeOptions EightBitSetOptions(const std::filesystem::path& dir) {
  TilesSynthesizeOptions synth;
  synth.output = dir.string();
  synth.bits = 8;
  synth.seed = 4;
  return synth;
}

}  // namespace fvm::workflows
