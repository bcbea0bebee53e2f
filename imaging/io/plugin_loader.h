#pragma once
// Optional parts of fvm built as plugins (CMake MODULE libraries) and loaded with dlopen the first time a file
// format needs them, so that commands which never meet that format do not pay for the library behind it.
//
// Where a plugin is looked for: $FVM_PLUGIN_DIR when set (and only there, so that a test can hide the plugins);
// else <directory of the executable>/../lib/fvm (build/fvm/fvm and an installed <prefix>/bin/fvm alike); else, from
// the shared object holding the loader (the Python module), ../lib/fvm in the build tree and <prefix>/lib/fvm once
// installed in <prefix>/lib/python3/dist-packages; else the build tree's plugin directory, fixed at configure time.

#include <string_view>

namespace fvm::imaging {

struct PluginSpec {
  const char* file;            // "libfvm_image_oiio.so"
  const char* entry;           // the extern "C" function returning the plugin's function table
  const char* library;         // what it wraps, for messages: "OpenImageIO"
  const char* debian_package;  // what to install when it cannot be loaded: "libopenimageio2.4"
};

// Loads the plugin once per process (thread-safe) and returns what its entry function returned. When it cannot
// be loaded, every call throws InputError "<action> needs <library>: <file> could not be loaded (<why>);
// install the Debian package <package>". Loaded plugins are never unloaded.
const void* LoadPlugin(const PluginSpec& spec, std::string_view action);

}  // namespace fvm::imaging
