#!/usr/bin/env bash
# The one entry script: installs what is missing (Debian packages, as root), configures and builds fvm, then
#   bash run.sh sample     calibrates the bundled sample batch and prints the result
#   bash run.sh test       what CI runs: the Release suite, then the sanitizer suite, then 2000 fuzzing executions
#                          per reader, then the Debian package installed, used from outside the tree and removed
#                          (about 35 minutes from scratch on 2 cores)
#   bash run.sh quick      the Release suite only (build/), with the fuzzers' regression inputs through the CLI, then
#                          the Python module's tests (pytest)
#   bash run.sh sanitize   the same tests built with AddressSanitizer and UndefinedBehaviorSanitizer (build-asan/)
#   bash run.sh fuzz [N]   every reader's libFuzzer target, N executions each (build-fuzz/, clang)
#   bash run.sh package    builds everything (man pages included) and packs build/fvm_<version>_<arch>.deb (CPack)
#   bash run.sh build      only builds
set -euo pipefail
cd "$(dirname "$0")"
what="${1:-sample}"

# gwyddion and libgwyddion20-dev (with the GTK 2, GtkGLExt and FFTW headers its pkg-config file requires): the
# independent reader that the tests of the instrument-file readers compare fvm with (tests/gwyddion).
packages=(cmake ninja-build ccache g++ pkg-config clang libclang-rt-14-dev
  libeigen3-dev libceres-dev libopencv-dev libpcl-dev libopenimageio-dev openimageio-tools
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev libfmt-dev libboost-dev libplplot-dev
  libzip-dev libpugixml-dev libssl-dev zlib1g-dev libhdf5-dev libtbb-dev librsvg2-bin
  gwyddion libgwyddion20-dev libgtk2.0-dev libgtkglext1-dev libfftw3-dev
  python3-dev python3-numpy python3-pytest python3-pybind11 pybind11-dev
  python3-sphinx python3-myst-parser dpkg-dev man-db)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  if [[ $(id -u) -eq 0 ]]; then
    echo "run.sh: installing ${missing[*]}" >&2
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  else
    echo "run.sh: missing Debian packages; run as root or: sudo apt-get install --no-install-recommends ${missing[*]}" >&2
    exit 1
  fi
fi

configure_release() {
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
}
build_release() {
  configure_release
  cmake --build build
}

# The Python module's tests (python/tests) against the module and the executable just built: `import fvm` from
# build/python, with Debian's interpreter (the one python/CMakeLists.txt builds for, where python3-numpy and
# python3-pytest are). Their closing line reads like ctest's ("N passed").
python_tests() {
  PYTHONDONTWRITEBYTECODE=1 PYTHONPATH="$PWD/build/python" /usr/bin/python3 -m pytest -q -p no:cacheprovider python/tests
}

# The whole suite again with AddressSanitizer and UndefinedBehaviorSanitizer: any report fails the test that
# made it (UBSan aborts instead of printing and going on). Benchmarks are not built here.
sanitize() {
  # -O1: the sanitizers need no more, and Ceres' templates compile in about half the time of -O3.
  local flags="-O1 -DNDEBUG -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=None -DFVM_BENCH=OFF -DFVM_PYTHON=OFF \
    -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_C_FLAGS="$flags" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_MODULE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
  cmake --build build-asan
  # fvm_cli_numeric_options starts fvm 500 times only to parse options: 7 minutes under ASan on 2 cores. It stays in
  # the Release suite; the option layer runs under the sanitizers in the fuzz target option_values_fuzz.
  # intercept_tls_get_addr=0: GCC 12's LeakSanitizer, tracking the dynamic TLS of dlopened libraries (the image
  # plugin's OpenImageIO) on Debian 12's glibc, records blocks at garbage addresses and crashes at exit reading them
  # ("Tracer caught signal 11", "DTLS ... at 0x1e13"), depending on the binary's layout alone.
  ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:intercept_tls_get_addr=0" \
    LSAN_OPTIONS="suppressions=$PWD/tests/sanitizer/lsan.supp:print_suppressions=0" \
    UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
    ctest --test-dir build-asan --output-on-failure -j2 -E '^fvm_cli_numeric_options$'
}

# The Debian package (cmake/package.cmake): build/fvm_<version>_<arch>.deb.
package() {
  build_release
  (cd build && cpack -G DEB >/dev/null)
  ls build/fvm_*.deb
}

fuzz() {
  if [[ -f tests/fuzz/run.sh ]]; then bash tests/fuzz/run.sh "$@"; fi
}

case "$what" in
  build) build_release ;;
  sample)
    # Only the executable and its format plugins: the sample needs no test, benchmark or fuzz target.
    configure_release
    cmake --build build --target fvm
    build/fvm/fvm calibrate samples/bar17 --model 27 -o build/sample-calibration.json --report build/sample-report
    ;;
  sanitize) sanitize ;;
  package) package ;;
  fuzz) shift; fuzz "$@" ;;
  quick)
    build_release
    ctest --test-dir build --output-on-failure -j2
    python_tests
    ;;
  test)
    start=$SECONDS
    step() { echo "run.sh test: $1 ($(((SECONDS - start) / 60)) min so far)" >&2; }
    step "Release build and tests"
    build_release
    ctest --test-dir build --output-on-failure -j2
    step "Python module tests"
    python_tests
    step "AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
    sanitize
    step "fuzzing every reader, 2000 executions each"
    fuzz 2000
    step "the Debian package: built, installed, used from outside the tree, removed"
    package
    bash tests/install/check_package.sh
    step "all suites passed"
    ;;
  *) echo "run.sh: unknown target '$what' (use sample, test, quick, sanitize, fuzz, package or build)" >&2; exit 2 ;;
esac
