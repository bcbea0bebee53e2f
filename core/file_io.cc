#include "core/file_io.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <random>
#include <system_error>

#include "core/input_error.h"

namespace fvm {
namespace {

// Beside the target so that the rename stays within one file system; the process id, a counter and a random
// part keep concurrent writers and leftovers of crashed ones apart.
std::filesystem::path TemporaryBeside(const std::filesystem::path& path) {
  static std::atomic<unsigned> counter{0};
  thread_local std::mt19937_64 random{std::random_device{}()};
  std::string name = ".";
  name += path.stem().string();
  name +=
      ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" + std::to_string(random() % 1000000);
  name += path.extension().string();
  return path.parent_path() / name;
}

[[noreturn]] void FailWrite(const std::filesystem::path& path, const std::string& why) {
  throw InputError(path.string() + ": cannot write (" + why +
                   "); check that the directory exists, is writable and has free space");
}

void RemoveQuietly(const std::filesystem::path& path) {
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
}

void CheckExists(const std::filesystem::path& path) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (error || !std::filesystem::exists(status)) {
    throw InputError(path.string() + ": no such file; check the path");
  }
  if (std::filesystem::is_directory(status)) {
    throw InputError(path.string() + ": is a directory, not a file; name a surface or point-cloud file");
  }
}

}  // namespace

std::size_t CheckReadableFile(const std::filesystem::path& path) {
  CheckExists(path);
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (error) throw InputError(path.string() + ": cannot read its size (" + error.message() + ")");
  if (size == 0) throw InputError(path.string() + ": the file is empty; export or copy it again");
  return static_cast<std::size_t>(size);
}

std::string ReadFileBytes(const std::filesystem::path& path, std::size_t max_bytes) {
  CheckExists(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open (" + std::strerror(errno) + "); check its permissions");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw InputError(path.string() + ": cannot tell its size; is it a regular file?");
  if (static_cast<std::size_t>(size) > max_bytes) {
    throw InputError(path.string() + ": " + std::to_string(size) + " bytes is more than the " +
                     std::to_string(max_bytes) + " a surface file may have; is this the right file?");
  }
  in.seekg(0, std::ios::beg);
  std::string bytes(static_cast<std::size_t>(size), '\0');
  if (!in.read(bytes.data(), size)) throw InputError(path.string() + ": read failed; is the file still there?");
  return bytes;
}

std::string ReadFileHead(const std::filesystem::path& path, std::size_t max_bytes) {
  CheckExists(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open (" + std::strerror(errno) + "); check its permissions");
  std::string bytes(max_bytes, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(max_bytes));
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  return bytes;
}

void WriteFileAtomically(const std::filesystem::path& path, std::string_view bytes) {
  WriteThroughTemporary(path, [&](const std::filesystem::path& temporary) {
    // stdio rather than ofstream: fflush + fsync make the content durable before the rename, so that after a
    // crash the target holds the old or the new content, never a truncated one.
    std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(temporary.c_str(), "wbx"), &std::fclose);
    if (!file) FailWrite(path, std::strerror(errno));
    if (std::fwrite(bytes.data(), 1, bytes.size(), file.get()) != bytes.size() || std::fflush(file.get()) != 0 ||
        ::fsync(::fileno(file.get())) != 0) {
      FailWrite(path, std::strerror(errno));
    }
    if (std::fclose(file.release()) != 0) FailWrite(path, std::strerror(errno));
  });
}

void WriteThroughTemporary(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path& temporary)>& write) {
  if (path.filename().empty()) FailWrite(path, "the path names a directory, not a file");
  const std::filesystem::path temporary = TemporaryBeside(path);
  try {
    write(temporary);
  } catch (...) {
    RemoveQuietly(temporary);
    throw;
  }
  if (!std::filesystem::exists(temporary)) FailWrite(path, "the writer produced no file");
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    RemoveQuietly(temporary);
    FailWrite(path, error.message());
  }
}

}  // namespace fvm
