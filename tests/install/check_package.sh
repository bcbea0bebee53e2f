#!/usr/bin/env bash
# The Debian package as a user meets it (run.sh test runs this as root after `run.sh package`): installs
# build/fvm_*.deb with apt-get, then, from a directory outside the source and build trees, runs the command, the
# Python module and the man pages, builds tests/install/consumer against the installed CMake package and checks
# that it calibrates the sample as `fvm calibrate` does, removes the package, and fails if any file it installed
# is left. Usage: bash tests/install/check_package.sh [DEB]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
deb="${1:-$(ls "$root"/build/fvm_*.deb | head -n 1)}"
fail() { echo "check_package: FAILED: $*" >&2; exit 1; }
if dpkg-query -W -f='${Status}' fvm 2>/dev/null | grep -q "install ok installed"; then
  fail "a package fvm is already installed; remove it first (apt-get remove fvm)"
fi

DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$deb" >/dev/null
work="$(mktemp -d /tmp/fvm-package-check.XXXXXX)"
trap 'rm -rf "$work"' EXIT
cd "$work"
files="$work/files.txt"
dpkg -L fvm > "$files"

# Nothing may come from the build tree: the installed programs must not even see it.
export FVM_PLUGIN_DIR=
[[ "$(command -v fvm)" == /usr/bin/fvm ]] || fail "fvm on PATH is $(command -v fvm), not /usr/bin/fvm"
version="$(fvm --version)"
echo "check_package: $version"
[[ "$version" =~ ^fvm\ [0-9]+\.[0-9]+\.[0-9]+\ \(commit\ [0-9a-f]{12}(-dirty)?\)$ ]] ||
  fail "fvm --version printed '$version'"
fvm calibrate /usr/share/fvm/samples/bar17 --model 27 -o c.json --json > calibrate.json
[[ -s c.json ]] || fail "fvm calibrate wrote no c.json"
# An image needs the OpenImageIO plugin: found in /usr/lib/fvm from /usr/bin/fvm.
fvm simulate fvm-batch -o raw --seed 3 --surfaces tif --validation-placements 0 --surface-pixel-mm 0.2 > /dev/null ||
  fail "fvm simulate fvm-batch --surfaces tif (writes TIFF through the image plugin)"
# The plugin both front ends load is the installed one, even with a build tree on the disk (the dynamic linker
# names every file it opens under LD_DEBUG=files).
plugin_loaded() { LD_DEBUG=files "$@" 2>&1 >/dev/null | grep -o "file=[^ ]*libfvm_image_oiio.so" | head -n 1; }
loaded="$(plugin_loaded fvm info raw/id-x.free.tif --pixel-mm 0.2 --json)"
[[ "$loaded" == "file=/usr/lib/fvm/libfvm_image_oiio.so" ]] || fail "fvm info on a TIFF loaded '$loaded'"
# A Zygo DATX needs the HDF5 plugin, the installed one; the command itself links no HDF5.
loaded="$(LD_DEBUG=files fvm info "$root/tests/fuzz/corpus/datx/nanometres.datx" --json 2>&1 >/dev/null |
  grep -o "file=[^ ]*libfvm_datx_hdf5.so" | head -n 1)"
[[ "$loaded" == "file=/usr/lib/fvm/libfvm_datx_hdf5.so" ]] || fail "fvm info on a DATX loaded '$loaded'"
! ldd /usr/bin/fvm | grep -q libhdf5 || fail "/usr/bin/fvm links HDF5 (it belongs in the DATX plugin)"
# An X3P (like PLUx and LEXT) needs the plugin of the zip- and XML-based formats, the installed one; the command
# itself links no libzip, libcrypto or pugixml.
loaded="$(LD_DEBUG=files fvm info "$root/tests/fuzz/corpus/x3p/binary-d.x3p" --json 2>&1 >/dev/null |
  grep -o "file=[^ ]*libfvm_zip_xml_formats.so" | head -n 1)"
[[ "$loaded" == "file=/usr/lib/fvm/libfvm_zip_xml_formats.so" ]] || fail "fvm info on an X3P loaded '$loaded'"
! ldd /usr/bin/fvm | grep -q "libzip\|libcrypto\|libpugixml" ||
  fail "/usr/bin/fvm links libzip, libcrypto or pugixml (they belong in the plugin libfvm_zip_xml_formats.so)"
# Calottes found in images need the OpenCV plugin, a report the report plugin: both the installed ones.
loaded="$(LD_DEBUG=files fvm calibrate raw --model 9 --pixel-mm 0.2 -o raw-calibration.json --report report 2>&1 >/dev/null |
  grep -o "file=[^ ]*libfvm_\(imaging_opencv\|report\)\.so" | sort -u | tr '\n' ' ')"
[[ "$loaded" == "file=/usr/lib/fvm/libfvm_imaging_opencv.so file=/usr/lib/fvm/libfvm_report.so " ]] ||
  fail "fvm calibrate on raw TIFF exports with --report loaded '$loaded'"
[[ -s report/index.html ]] || fail "fvm calibrate --report wrote no report/index.html"
/usr/bin/python3 -c "import fvm, sys; print('check_package: import fvm', fvm.__version__, fvm.__file__)"
[[ "$(/usr/bin/python3 -c 'import fvm; print(fvm.__file__)')" == /usr/lib/python3/dist-packages/* ]] ||
  fail "import fvm did not take the installed module"
loaded="$(plugin_loaded /usr/bin/python3 -c "import fvm; fvm.read_surface('raw/id-x.free.tif', dx_mm=0.2)")"
[[ "$loaded" == "file=/usr/lib/fvm/libfvm_image_oiio.so" ]] || fail "fvm.read_surface on a TIFF loaded '$loaded'"
man -w fvm > /dev/null || fail "man -w fvm"
man -w fvm-calibrate > /dev/null || fail "man -w fvm-calibrate"

# Another project on the installed libraries: the same distance figure as fvm calibrate's JSON. Its configure step
# fails when the package exports a target, or names an fvm library in a link interface, other than as fvm::<name>.
cmake -S "$root/tests/install/consumer" -B consumer -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build consumer > /dev/null
consumer/fvm_consumer /usr/share/fvm/samples/bar17 > consumer.txt
/usr/bin/python3 - calibrate.json consumer.txt <<'PY'
import json, re, sys
cli = json.load(open(sys.argv[1]))["validation"]["distances"]["rms_um"]
lib = float(re.search(r"([0-9.]+) um rms", open(sys.argv[2]).read()).group(1))
print(f"check_package: consumer {lib:.6f} um, fvm calibrate {cli:.6f} um (distances after compensation, rms)")
sys.exit(0 if abs(lib - cli) <= 1e-6 * max(1.0, abs(cli)) else 1)
PY

DEBIAN_FRONTEND=noninteractive apt-get remove -y -qq fvm > /dev/null
left=()
while IFS= read -r path; do
  [[ -z "$path" || "$path" == "/." ]] && continue
  # Directories shared with other packages (/usr/bin, /usr/share/man/man1) stay; fvm's own must go.
  if [[ -d "$path" && ! -L "$path" ]]; then
    [[ -n "$(dpkg -S "$path" 2>/dev/null)" ]] && continue
    [[ "$path" == */fvm || "$path" == */fvm/* ]] && left+=("$path")
  elif [[ -e "$path" || -L "$path" ]]; then
    left+=("$path")
  fi
done < "$files"
((${#left[@]} == 0)) || fail "apt-get remove left ${#left[@]} paths behind: ${left[*]:0:10}"
echo "check_package: $(grep -c . "$files") paths installed and removed; 9 checks passed"
