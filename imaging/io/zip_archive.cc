#include "imaging/io/zip_archive.h"

#include <zip.h>

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "core/input_error.h"

namespace fvm::imaging {
namespace {

std::string ErrorText(zip_error_t* error) {
  const char* text = zip_error_strerror(error);
  return text ? text : "unknown libzip error";
}

// 2000-01-01 00:00 UTC: any fixed time would do; this one is valid as a DOS date in every time zone.
constexpr time_t kFixedEntryTime = 946684800;

}  // namespace

struct ZipReader::Impl {
  std::string bytes;  // libzip reads from this buffer without copying: it must outlive `archive`
  std::string name;
  zip_t* archive = nullptr;

  // Exact name first; then as some Windows writers store it (backslashes, other case).
  zip_int64_t Locate(const std::string& entry) const {
    const zip_int64_t exact = zip_name_locate(archive, entry.c_str(), 0);
    if (exact >= 0) return exact;
    std::string windows = entry;
    std::replace(windows.begin(), windows.end(), '/', '\\');
    const zip_int64_t backslashed = zip_name_locate(archive, windows.c_str(), ZIP_FL_NOCASE);
    return backslashed >= 0 ? backslashed : zip_name_locate(archive, entry.c_str(), ZIP_FL_NOCASE);
  }

  [[noreturn]] void Fail(const std::string& problem) const {
    throw InputError(name + ": " + problem + "; the file is damaged or incomplete: copy or export it again");
  }
};

ZipReader::ZipReader(std::string bytes, std::string name) : impl_(std::make_unique<Impl>()) {
  impl_->bytes = std::move(bytes);
  impl_->name = std::move(name);
  if (impl_->bytes.empty()) throw InputError(impl_->name + ": the file is empty; export it again");
  zip_error_t error;
  zip_error_init(&error);
  zip_source_t* source = zip_source_buffer_create(impl_->bytes.data(), impl_->bytes.size(), 0, &error);
  if (source == nullptr) {
    const std::string text = ErrorText(&error);
    zip_error_fini(&error);
    throw std::runtime_error("libzip cannot wrap a buffer: " + text);
  }
  impl_->archive = zip_open_from_source(source, ZIP_RDONLY, &error);
  if (impl_->archive == nullptr) {
    zip_source_free(source);
    const std::string text = ErrorText(&error);
    zip_error_fini(&error);
    impl_->Fail("not a readable zip archive (" + text + ")");
  }
  zip_error_fini(&error);
}

ZipReader::~ZipReader() {
  if (impl_ && impl_->archive) zip_discard(impl_->archive);
}

bool ZipReader::Has(const std::string& entry) const { return impl_->Locate(entry) >= 0; }

std::vector<std::string> ZipReader::Entries() const {
  std::vector<std::string> names;
  const zip_int64_t count = zip_get_num_entries(impl_->archive, 0);
  for (zip_int64_t i = 0; i < count; ++i) {
    const char* entry = zip_get_name(impl_->archive, static_cast<zip_uint64_t>(i), 0);
    if (entry) names.emplace_back(entry);
  }
  return names;
}

std::size_t ZipReader::DeclaredSize(const std::string& entry) const {
  const zip_int64_t index = impl_->Locate(entry);
  if (index < 0) impl_->Fail("has no entry '" + entry + "'");
  zip_stat_t stat;
  zip_stat_init(&stat);
  if (zip_stat_index(impl_->archive, static_cast<zip_uint64_t>(index), 0, &stat) != 0 ||
      !(stat.valid & ZIP_STAT_SIZE)) {
    impl_->Fail("cannot read the directory record of '" + entry + "'");
  }
  return static_cast<std::size_t>(stat.size);
}

std::string ZipReader::Read(const std::string& entry, std::size_t max_bytes) const {
  const zip_int64_t index = impl_->Locate(entry);
  if (index < 0) impl_->Fail("has no entry '" + entry + "'");
  const std::size_t declared = DeclaredSize(entry);
  if (declared > max_bytes) {
    impl_->Fail("entry '" + entry + "' declares " + std::to_string(declared) + " bytes, more than the " +
                std::to_string(max_bytes) + " its description allows");
  }
  zip_file_t* file = zip_fopen_index(impl_->archive, static_cast<zip_uint64_t>(index), 0);
  if (file == nullptr) {
    impl_->Fail("cannot open entry '" + entry + "' (" + ErrorText(zip_get_error(impl_->archive)) + ")");
  }
  // Grow while reading rather than trusting the declared size: a lying directory costs only what arrives.
  std::string content;
  char buffer[1 << 16];
  while (true) {
    const zip_int64_t n = zip_fread(file, buffer, sizeof buffer);
    if (n < 0) {
      const std::string text = ErrorText(zip_file_get_error(file));
      zip_fclose(file);
      impl_->Fail("entry '" + entry + "' is corrupt (" + text + ")");
    }
    if (n == 0) break;
    if (content.size() + static_cast<std::size_t>(n) > declared) {
      zip_fclose(file);
      impl_->Fail("entry '" + entry + "' holds more than the " + std::to_string(declared) + " bytes it declares");
    }
    content.append(buffer, static_cast<std::size_t>(n));
  }
  zip_fclose(file);
  if (content.size() != declared) {
    impl_->Fail("entry '" + entry + "' holds " + std::to_string(content.size()) + " bytes, not the " +
                std::to_string(declared) + " it declares");
  }
  return content;
}

std::string BuildZip(const std::vector<ZipEntry>& entries) {
  zip_error_t error;
  zip_error_init(&error);
  const auto fail = [&](const std::string& what) {
    const std::string text = ErrorText(&error);
    zip_error_fini(&error);
    throw std::runtime_error("libzip: " + what + ": " + text);
  };
  zip_source_t* target = zip_source_buffer_create(nullptr, 0, 0, &error);
  if (target == nullptr) fail("cannot create a buffer");
  zip_t* archive = zip_open_from_source(target, ZIP_TRUNCATE, &error);
  if (archive == nullptr) {
    zip_source_free(target);
    fail("cannot open an archive in memory");
  }
  zip_source_keep(target);  // zip_close would free it; we still read the result from it
  const auto fail_archive = [&](const std::string& what) {
    zip_error_set(&error, zip_error_code_zip(zip_get_error(archive)), zip_error_code_system(zip_get_error(archive)));
    zip_discard(archive);
    zip_source_free(target);
    fail(what);
  };
  for (const ZipEntry& entry : entries) {
    // The contents outlive zip_close, so libzip may read them in place.
    zip_source_t* source = zip_source_buffer(archive, entry.content.data(), entry.content.size(), 0);
    if (source == nullptr) fail_archive("cannot wrap " + entry.name);
    const zip_int64_t index = zip_file_add(archive, entry.name.c_str(), source, ZIP_FL_ENC_UTF_8 | ZIP_FL_OVERWRITE);
    if (index < 0) {
      zip_source_free(source);
      fail_archive("cannot add " + entry.name);
    }
    const auto i = static_cast<zip_uint64_t>(index);
    if (zip_set_file_compression(archive, i, ZIP_CM_DEFLATE, 0) != 0 ||
        zip_file_set_mtime(archive, i, kFixedEntryTime, 0) != 0) {
      fail_archive("cannot set the attributes of " + entry.name);
    }
  }
  if (zip_close(archive) != 0) fail_archive("cannot write the archive");

  std::string bytes;
  zip_stat_t stat;
  zip_stat_init(&stat);
  if (zip_source_open(target) != 0 || zip_source_stat(target, &stat) != 0) {
    zip_source_free(target);
    throw std::runtime_error("libzip: cannot read back the archive built in memory");
  }
  bytes.resize(static_cast<std::size_t>(stat.size));
  const zip_int64_t n = zip_source_read(target, bytes.data(), bytes.size());
  zip_source_close(target);
  zip_source_free(target);
  zip_error_fini(&error);
  if (n < 0 || static_cast<std::size_t>(n) != bytes.size()) {
    throw std::runtime_error("libzip: short read of the archive built in memory");
  }
  return bytes;
}

}  // namespace fvm::imaging
