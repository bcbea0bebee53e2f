#pragma once
// Whole-file reads and atomic writes, for every module that reads or writes user files.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace fvm {

// The whole file. Throws InputError naming the path when it is missing, a directory, unreadable or larger
// than max_bytes (a guard against reading a disk image by mistake).
std::string ReadFileBytes(const std::filesystem::path& path, std::size_t max_bytes = std::size_t{1} << 34);

// The first max_bytes of the file (all of it when shorter), for telling formats apart. Same errors as
// ReadFileBytes.
std::string ReadFileHead(const std::filesystem::path& path, std::size_t max_bytes);

// For readers that open the file themselves (PCL, OpenImageIO): throws the same InputError as ReadFileBytes
// when the file is missing or a directory, and when it is empty. Returns its size in bytes.
std::size_t CheckReadableFile(const std::filesystem::path& path);

// Writes the whole file or nothing: to a temporary file beside the target, then renamed over it.
void WriteFileAtomically(const std::filesystem::path& path, std::string_view bytes);

// For libraries that only write to a path (PCL, OpenImageIO): `write` writes the temporary path it is given
// (same directory, same extension, so that extension-based writers pick the right format), which is then
// renamed over `path`. If `write` throws, the temporary file is removed and the exception passes on.
void WriteThroughTemporary(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path& temporary)>& write);

}  // namespace fvm
