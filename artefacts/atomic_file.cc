#include "artefacts/atomic_file.h"

#include <fcntl.h>
#include <fmt/core.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <random>
#include <string>
#include <system_error>

#include "imaging/input_error.h"

namespace fvm {
namespace {

// A name no other writer uses: the process id keeps processes apart, the counter threads, the random part
// leftovers of an earlier process with a recycled id. The leading dot keeps it out of casual listings.
std::filesystem::path TempPathBeside(const std::filesystem::path& path) {
  static std::atomic<unsigned> counter{0};
  thread_local std::mt19937_64 random{std::random_device{}()};
  return path.parent_path() /
         fmt::format(".{}.tmp-{}-{}-{}", path.filename().string(), ::getpid(), counter++, random() % 1000000);
}

[[noreturn]] void Fail(const std::filesystem::path& path, const std::string& why) {
  throw InputError(path.string() + ": cannot write (" + why +
                   "); check that the directory exists, is writable and has free space");
}

}  // namespace

void WriteFileAtomically(const std::filesystem::path& path, std::string_view content) {
  if (path.filename().empty()) Fail(path, "the path names a directory, not a file");
  const std::filesystem::path temp = TempPathBeside(path);

  // POSIX calls rather than ofstream: they report why a write failed and let us fsync before the rename, so
  // that after a crash the target holds either the old or the new content, never a truncated one.
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) Fail(path, std::strerror(errno));
  const auto discard = [&](const std::string& why) {
    ::close(fd);
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    Fail(path, why);
  };
  const char* data = content.data();
  size_t left = content.size();
  while (left > 0) {
    const ssize_t written = ::write(fd, data, left);
    if (written < 0) {
      if (errno == EINTR) continue;
      discard(std::strerror(errno));
    }
    data += written;
    left -= static_cast<size_t>(written);
  }
  if (::fsync(fd) != 0) discard(std::strerror(errno));
  if (::close(fd) != 0) {
    const std::string why = std::strerror(errno);
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    Fail(path, why);
  }

  std::error_code error;
  std::filesystem::rename(temp, path, error);
  if (error) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    Fail(path, error.message());
  }
}

}  // namespace fvm
