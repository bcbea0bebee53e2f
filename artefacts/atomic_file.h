#pragma once
// Writes a whole file or nothing: the content goes to a temporary file beside the target, then is renamed
// over it, so a failure never leaves a half-written output.

#include <filesystem>
#include <string_view>

namespace fvm {

// Throws InputError naming the path when the directory cannot be written.
void WriteFileAtomically(const std::filesystem::path& path, std::string_view content);

}  // namespace fvm
