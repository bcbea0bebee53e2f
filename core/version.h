#pragma once
// The version of fvm and the commit it was built from, for `fvm --version` and the Python module's __version__.
// Defined in a source that the build writes (cmake/version.cmake) into the small library fvm_version, which only
// the two front ends link: a new commit recompiles one file and relinks them, not every test.

namespace fvm {

// The release, "0.1.0" (project() in CMakeLists.txt).
const char* Version();
// The git commit of the source tree (12 hex digits, "-dirty" when it had uncommitted changes), or "unknown" when
// built outside a git checkout (a source tarball).
const char* GitCommit();

}  // namespace fvm
