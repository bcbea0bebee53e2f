#include "artefacts/atomic_file.h"

#include "imaging/file_io.h"

namespace fvm {

// One implementation serves every layer: imaging's (temporary file beside the target, fsync, rename).
void WriteFileAtomically(const std::filesystem::path& path, std::string_view content) {
  imaging::WriteFileBytesAtomically(path, content);
}

}  // namespace fvm
