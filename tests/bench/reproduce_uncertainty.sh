#!/usr/bin/env bash
# Reproduces the published Monte Carlo studies in simulation with `fvm uncertainty` (keys: README, References):
#   plane:  400 x 400 mm, 1000 runs: initial 77.39 +- 40.91 um -> residual 12.34 +- 7.06 um ([Aguado 2017]);
#   mesh:   75 points, 5 x 5 x 3 at 100 mm, 1000 runs: residual N(13.77, 5.02) um, 95 % bound 23.81 um, worst ~50 um
#           ([Pérez 2019 Sensors] section 3);
#   placement: tracker positions ranked by the Monte Carlo maximum error; a good placement cuts it by ~30 %
#           ([Pérez 2019 Sensors] section 4).
# One simulated XFYZ machine (seed 1, 400 x 400 x 200 mm, tool 0,0,100 mm, scaled with --mean-error-um so that the
# plane's initial mean error is near the published 77 um), the tracker 1.3 m from the mesh centre with the published
# noise. The plane is the mesh's z = 0 layer (25 points); on a plane the tracker pose cannot be estimated (a rotation
# about the plane's normal is free), so it is held there (--pose), as the published plane study did.
#
# Then the check on repeat measurements ([GUM Supplement 1]: a prediction of what a repeat would show): the same
# machine read REPEATS times (default 8), each time with fresh tracker noise on its readings and on its validation
# readings (the mesh at 50 mm, read like the others: real validation readings are noisy too), each verified with
# `fvm verify --validate`; `fvm uncertainty` from the first repeat alone predicts their validation mean error. The
# same with the simulator's noise-free validation readings.
#
# Usage: bash tests/bench/reproduce_uncertainty.sh [FVM] [RUNS] [REPEATS]
#        (FVM default build/fvm/fvm, RUNS default 1000, REPEATS default 8)
# Needs jq. About 30 s on 2 cores.
set -euo pipefail

FVM=${1:-build/fvm/fvm}
RUNS=${2:-1000}
REPEATS=${3:-8}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
POSE=900,-900,400,0,0,30

"$FVM" simulate tracker --machine 400x400x200 --points mesh:100,100,100 --tool 0,0,100 --pose $POSE --seed 1 \
  --mean-error-um 70 --validation mesh:50,50,50 -o "$WORK/plan" >/dev/null
# The plane: the z = 0 rows of the readings (comments and header kept).
awk -F, '/^#/ {print; next} !h {print; h=1; for (i = 1; i <= NF; i++) if ($i == "z") zc = i; next} $zc == 0' \
  "$WORK/plan/readings.csv" > "$WORK/plane.csv"

row() {  # name published json
  jq -r --arg name "$1" --arg published "$2" '
    "| \($name) | \(.runs) | \(.pooled_um.initial.mean * 100 | round / 100) +- \(.pooled_um.initial.sd * 100 | round / 100)"
    + " | \(.pooled_um.model_error.mean * 100 | round / 100) +- \(.pooled_um.model_error.sd * 100 | round / 100)"
    + " | \(.pooled_um.model_error.p95 * 100 | round / 100) | \(.pooled_um.model_error.max * 10 | round / 10)"
    + " | \(.seconds * 10 | round / 10) | \($published) |"' <<<"$3"
}
echo "| study | runs | initial (um) | residual: model - truth (um) | 95 % (um) | max (um) | s | published |"
echo "|---|---|---|---|---|---|---|---|"
for order in 1 2; do
  out=$("$FVM" uncertainty "$WORK/plane.csv" --machine 400x400x200 --order $order --tool 0,0,100 --pose $POSE \
    --runs "$RUNS" --seed 1 --json)
  row "plane 25, order $order" "77.39 +- 40.91 -> 12.34 +- 7.06" "$out"
done
for order in 1 2 3; do
  out=$("$FVM" uncertainty "$WORK/plan/readings.csv" --order $order --tool 0,0,100 --fit-pose --runs "$RUNS" --seed 1 \
    --validate "$WORK/plan/validation.csv" --json)
  row "mesh 75, order $order" "N(13.77, 5.02), 95 % 23.81, max ~50" "$out"
done
echo
echo "Tracker placement (mesh 75, order 2): a box beside the machine, 5 x 5 x 5 positions"
"$FVM" uncertainty "$WORK/plan/readings.csv" --order 2 --tool 0,0,100 --runs 200 --seed 1 \
  --place-tracker -1000,-1500,0,1400,-600,1000 --place-steps 5 --place-confirm 3

echo
echo "Repeat measurements of the plan's machine (mesh 75, order 2): $REPEATS repeats, fresh noise on readings and validation"
observed=()
for ((k = 1; k <= REPEATS; ++k)); do
  "$FVM" simulate tracker --errors "$WORK/plan/truth.json" --machine 400x400x200 --points mesh:100,100,100 --tool 0,0,100 --pose $POSE \
    --seed $((100 + k)) -o "$WORK/r$k" >/dev/null
  "$FVM" simulate tracker --errors "$WORK/plan/truth.json" --machine 400x400x200 --points mesh:50,50,50 --tool 0,0,100 --pose $POSE \
    --seed $((200 + k)) -o "$WORK/v$k" >/dev/null
  observed+=("$("$FVM" verify "$WORK/r$k/readings.csv" --order 2 --tool 0,0,100 --fit-pose \
    --validate "$WORK/v$k/readings.csv" --json | jq '.validation.final.mean_um')")
done
summary() {  # label, predicted "mean sd"; the observed values on stdin
  awk -v label="$1" -v p="$2" '
  { x[NR] = $1; s += $1 } END {
    m = s / NR; for (i = 1; i <= NR; ++i) v += (x[i] - m) ^ 2; sd = sqrt(v / (NR - 1)); split(p, q, " ")
    printf "%s: %d repeats %.2f +- %.2f um; Monte Carlo from the first %.2f +- %.2f um; ratios: mean %.2f, spread %.2f\n",
      label, NR, m, sd, q[1], q[2], q[1] / m, q[2] / sd }'
}
predicted=$("$FVM" uncertainty "$WORK/r1/readings.csv" --order 2 --tool 0,0,100 --fit-pose --runs "$RUNS" --seed 1 \
  --validate "$WORK/v1/readings.csv" --json | jq -r '"\(.validation_mean_um.mean) \(.validation_mean_um.sd)"')
printf '%s\n' "${observed[@]}" | summary "validation mean error" "$predicted"
observed=()
for ((k = 1; k <= REPEATS; ++k)); do
  "$FVM" simulate tracker --errors "$WORK/plan/truth.json" --machine 400x400x200 --points mesh:100,100,100 --tool 0,0,100 \
    --pose $POSE --seed $((100 + k)) --validation mesh:50,50,50 -o "$WORK/n$k" >/dev/null
  observed+=("$("$FVM" verify "$WORK/n$k/readings.csv" --order 2 --tool 0,0,100 --fit-pose \
    --validate "$WORK/n$k/validation.csv" --json | jq '.validation.final.mean_um')")
done
predicted=$("$FVM" uncertainty "$WORK/n1/readings.csv" --order 2 --tool 0,0,100 --fit-pose --runs "$RUNS" --seed 1 \
  --validate "$WORK/n1/validation.csv" --json | jq -r '"\(.validation_mean_um.mean) \(.validation_mean_um.sd)"')
printf '%s\n' "${observed[@]}" | summary "noise-free validation readings" "$predicted"
