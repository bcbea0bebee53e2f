#include "imaging/io/plugin_loader.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

#include "core/input_error.h"

namespace fvm::imaging {
namespace {

std::vector<std::filesystem::path> SearchDirectories() {
  if (const char* dir = std::getenv("FVM_PLUGIN_DIR"); dir != nullptr && *dir != '\0') return {dir};
  std::vector<std::filesystem::path> dirs;
  // Beside the executable first: an installed fvm (<prefix>/bin/fvm) takes its own <prefix>/lib/fvm even where a
  // build tree is still on the disk; for build/fvm/fvm this is the build tree's plugin directory.
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) dirs.push_back(exe.parent_path().parent_path() / "lib" / "fvm");
  // The shared object this code is linked into, when it is not the executable (the Python module: the process is
  // python3, whose directory says nothing about fvm's): build/python/../lib/fvm in the build tree, and the
  // installed module's path to <prefix>/lib/fvm (from <prefix>/lib/python3/dist-packages, CMake computes it).
  Dl_info self{};
  if (dladdr(reinterpret_cast<const void*>(&SearchDirectories), &self) != 0 && self.dli_fname != nullptr &&
      *self.dli_fname != '\0') {
    const std::filesystem::path object = std::filesystem::weakly_canonical(self.dli_fname, error);
    if (!error && object != exe) {
      dirs.push_back(object.parent_path().parent_path() / "lib" / "fvm");
#ifdef FVM_PLUGIN_DIR_FROM_PYTHON_MODULE
      dirs.push_back((object.parent_path() / FVM_PLUGIN_DIR_FROM_PYTHON_MODULE).lexically_normal());
#endif
    }
  }
#ifdef FVM_BUILD_PLUGIN_DIR
  dirs.emplace_back(FVM_BUILD_PLUGIN_DIR);  // the test executables, which live elsewhere in the build tree
#endif
  return dirs;
}

// What loading one plugin gave: the entry function's result, or why it failed.
struct Loaded {
  const void* table = nullptr;
  std::string failure;
};

Loaded Load(const PluginSpec& spec) {
  std::string failures;
  for (const std::filesystem::path& dir : SearchDirectories()) {
    const std::filesystem::path file = dir / spec.file;
    std::error_code error;
    if (!std::filesystem::exists(file, error)) {
      failures += (failures.empty() ? "" : "; ") + std::string("not in ") + dir.string();
      continue;
    }
    // RTLD_LOCAL: the plugin's libraries stay out of the global namespace; RTLD_NOW: a missing library or symbol
    // is reported here, not as a crash in the middle of a read.
    void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* why = dlerror();
      return {nullptr, why != nullptr ? why : file.string() + ": dlopen failed"};
    }
    using Entry = const void* (*)();
    const auto entry = reinterpret_cast<Entry>(dlsym(handle, spec.entry));
    if (entry == nullptr) return {nullptr, file.string() + " has no entry point " + spec.entry + " (a stale build?)"};
    return {entry(), ""};
  }
  return {nullptr, failures.empty() ? "no directory to look in" : failures};
}

}  // namespace

const void* LoadPlugin(const PluginSpec& spec, std::string_view action) {
  // One attempt per plugin and process: a failure is remembered, so that every file of that format gets the same
  // message and the others never notice.
  static std::mutex mutex;
  static std::map<std::string, Loaded> loaded;
  const Loaded* result = nullptr;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    auto it = loaded.find(spec.file);
    if (it == loaded.end()) it = loaded.emplace(spec.file, Load(spec)).first;
    result = &it->second;
  }
  if (result->table == nullptr) {
    throw InputError(std::string(action) + " needs " + spec.library + ": " + spec.file + " could not be loaded (" +
                     result->failure + "); install the Debian package " + spec.debian_package +
                     ", or point FVM_PLUGIN_DIR at the directory holding " + spec.file);
  }
  return result->table;
}

}  // namespace fvm::imaging
