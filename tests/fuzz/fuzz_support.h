#pragma once
// Shared by the libFuzzer targets (one per reader). A reader given any bytes either returns or throws
// fvm::InputError, the error a user sees as "file: what is wrong". Anything else that escapes (another
// exception, a crash, a hang, a leak, a sanitizer report) is a finding: the harness lets it through so that
// libFuzzer stops and saves the input.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <system_error>

#include "core/input_error.h"

namespace fvm::fuzz {

inline std::string_view Bytes(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// A directory of this process's own, removed at exit; readers that take a path read files written into it.
class ScratchDir {
 public:
  ScratchDir()
      : path_(std::filesystem::temp_directory_path() / ("fvm-fuzz-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  // Writes `bytes` to the file `name` in the directory (replacing it) and returns its path.
  std::filesystem::path Write(const std::string& name, std::string_view bytes) const {
    const std::filesystem::path file = path_ / name;
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return file;
  }

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

inline const ScratchDir& Scratch() {
  static const ScratchDir dir;
  return dir;
}

// Runs `read`; an InputError is the reader's correct answer to bad bytes, so it ends the run quietly.
template <typename Read>
void ReadExpectingInputErrorOnly(Read read) {
  try {
    read();
  } catch (const fvm::InputError&) {
  }
}

}  // namespace fvm::fuzz
