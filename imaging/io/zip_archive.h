#pragma once
// Zip containers (X3P is one) held in memory: read named entries with size limits and CRC checks, build an
// archive from named contents. A thin layer over libzip that keeps its types out of the public headers.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace fvm::imaging {

class ZipReader {
 public:
  // `name` is what errors call the archive (usually its path). Throws InputError when the bytes are not a
  // readable zip archive (truncated, corrupt central directory, empty).
  ZipReader(std::string bytes, std::string name);
  ~ZipReader();
  ZipReader(const ZipReader&) = delete;
  ZipReader& operator=(const ZipReader&) = delete;

  bool Has(const std::string& entry) const;
  std::vector<std::string> Entries() const;
  // The uncompressed size the archive declares for an entry (it may lie; Read checks what arrives).
  std::size_t DeclaredSize(const std::string& entry) const;
  // The entry's content. Throws InputError when it is missing, would exceed max_bytes, or does not inflate
  // to its declared size and CRC (a corrupt or truncated archive).
  std::string Read(const std::string& entry, std::size_t max_bytes) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct ZipEntry {
  std::string name;  // path inside the archive, '/'-separated
  std::string content;
};

// A deflate-compressed archive of the entries in the given order. Entry times are fixed, so that the same
// entries give the same bytes.
std::string BuildZip(const std::vector<ZipEntry>& entries);

}  // namespace fvm::imaging
