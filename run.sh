#!/usr/bin/env bash
# The one entry script: installs what is missing (Debian packages, as root), configures and builds fvm, then
#   bash run.sh sample   calibrates the bundled sample batch and prints the result
#   bash run.sh test     runs the whole test suite
#   bash run.sh build    only builds
set -euo pipefail
cd "$(dirname "$0")"
what="${1:-sample}"

packages=(cmake ninja-build ccache g++ pkg-config
  libeigen3-dev libceres-dev libopencv-dev libpcl-dev libopenimageio-dev openimageio-tools
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev libfmt-dev libboost-dev libplplot-dev
  libzip-dev libpugixml-dev libssl-dev)
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

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build

case "$what" in
  build) ;;
  sample)
    build/fvm/fvm calibrate samples/bar17 --model 27 -o build/sample-calibration.json --report build/sample-report
    ;;
  test) ctest --test-dir build --output-on-failure -j2 ;;
  *) echo "run.sh: unknown target '$what' (use sample, test or build)" >&2; exit 2 ;;
esac
