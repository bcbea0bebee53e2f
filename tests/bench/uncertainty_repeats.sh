#!/usr/bin/env bash
# The machine Monte Carlo (`fvm uncertainty --validate`) against independent repeats of one machine: ../shared/bench's
# trackergen.py (--truth rich: errors no polynomial follows; the published tracker noise) reads machine SEED again
# with fresh noise (--noise-seed 1..REPEATS); each repeat is verified with `fvm verify --validate` on the machine's
# noise-free validation mesh, and `fvm uncertainty` from each of the first STARTS repeats alone predicts the mean and
# the spread (sd) of the repeats' validation mean errors. Prints one line per seed and start: the ratios predicted /
# observed. The spread of a dozen repeats is known to ~20 % only (and trackergen's noise seeds 1-24 happen to be calm
# ones for every machine): use 200.
#
# Usage: bash tests/bench/uncertainty_repeats.sh [FVM] [SEEDS] [REPEATS] [STARTS] [RUNS]
#        (defaults build/fvm/fvm, 3,4,5,6,7,8, 200, 4, 200). Needs ../shared/bench and python3-numpy. About 2 minutes
#        a seed on 2 cores.
set -euo pipefail

FVM=$(realpath "${1:-build/fvm/fvm}")
SEEDS=${2:-3,4,5,6,7,8}
REPEATS=${3:-200}
STARTS=${4:-4}
RUNS=${5:-200}
BENCH=$(cd "$(dirname "$0")/../../../shared/bench" && pwd)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
OPTIONS=(--chain XFYZ --order 1 --tool 0,0,100 --fit-pose)

for seed in ${SEEDS//,/ }; do
  d=$WORK/$seed
  mkdir -p "$d"
  # trackergen's own main in one process (nothing written beside the bench).
  /usr/bin/python3 -B - "$BENCH" "$d" "$seed" "$REPEATS" <<'EOF'
import sys, io, contextlib
sys.path.insert(0, sys.argv[1]); import trackergen
d, seed, n = sys.argv[2], sys.argv[3], int(sys.argv[4])
for name, extra in [("val.csv", ["--step", "250,250,200"])] + [
        (f"d{k}.csv", ["--noise", "--noise-seed", str(k)]) for k in range(1, n + 1)]:
    sys.argv = ["trackergen.py", f"{d}/{name}", "--seed", seed, "--truth", "rich"] + extra
    with contextlib.redirect_stdout(io.StringIO()):
        trackergen.main()
EOF
  for k in $(seq 1 "$REPEATS"); do
    "$FVM" verify "$d/d$k.csv" "${OPTIONS[@]}" --validate "$d/val.csv" --json >"$d/v$k.json"
  done
  for s in $(seq 1 "$STARTS"); do
    "$FVM" uncertainty "$d/d$s.csv" "${OPTIONS[@]}" --runs "$RUNS" --seed 1 --validate "$d/val.csv" --json >"$d/mc$s.json"
  done
  /usr/bin/python3 - "$d" "$seed" "$REPEATS" "$STARTS" <<'EOF'
import sys, json, numpy as np
d, seed, n, starts = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
v = np.array([json.load(open(f"{d}/v{k}.json"))["validation"]["final"]["mean_um"] for k in range(1, n + 1)])
for s in range(1, starts + 1):
    m = json.load(open(f"{d}/mc{s}.json"))["validation_mean_um"]
    print(f"seed {seed}: {n} repeats {v.mean():.2f} +- {v.std(ddof=1):.2f} um; Monte Carlo from repeat {s} "
          f"{m['mean']:.2f} +- {m['sd']:.2f} um; ratios mean {m['mean'] / v.mean():.3f}, spread {m['sd'] / v.std(ddof=1):.3f}")
EOF
done
