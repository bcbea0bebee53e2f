#!/usr/bin/env bash
# Start-up cost of whole fvm processes: median wall time (s) and median peak resident memory (MB) over repeats,
# measured with /usr/bin/time (issue 15: light commands should start in < 50 ms and < 30 MB).
# Usage: tests/bench/startup.sh [path/to/fvm] [repeats]   (defaults: build/fvm/fvm, 15)
set -euo pipefail
fvm=${1:-build/fvm/fvm}
repeats=${2:-15}
root=$(cd "$(dirname "$0")/../.." && pwd)
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

measure() {
  local label=$1; shift
  "$fvm" "$@" >/dev/null 2>&1 || { echo "$label: fvm $* failed" >&2; return 1; }  # warm the page cache
  : >"$scratch/walls"
  : >"$scratch/rss"
  for _ in $(seq "$repeats"); do
    # /usr/bin/time prints wall time in 10 ms steps only: the wall time comes from the clock around it.
    local start end
    start=$(date +%s%N)
    /usr/bin/time -f "%M" -a -o "$scratch/rss" "$fvm" "$@" >/dev/null 2>&1
    end=$(date +%s%N)
    echo $(((end - start) / 1000)) >>"$scratch/walls"
  done
  local wall rss
  wall=$(awk '{ print $1 / 1e6 }' "$scratch/walls" | median)
  rss=$(awk '{ print $1 / 1024 }' "$scratch/rss" | median)
  printf '%-40s median %6.3f s  %6.1f MB  (%d runs)\n' "$label" "$wall" "$rss" "$repeats"
}

measure "fvm --version" --version
measure "fvm calibrate samples/bar17 --model 27" calibrate "$root/samples/bar17" --model 27 -o "$scratch/cal.json"
