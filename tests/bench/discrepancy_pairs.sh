#!/usr/bin/env bash
# The discrepancy workflow on every pair of catalogue effects hidden together (issue 14): for each pair and seed,
# `fvm simulate fvm-batch --hidden-effect A,B` then `fvm diagnose --json`. A case passes when both effects are named
# and the held-out gap at least halves. Prints one line per case, the pass table and the confusion matrix (hidden
# effect against named effects), then the outlier and clean-batch figures when asked.
#
#   bash tests/bench/discrepancy_pairs.sh [FVM] [SEEDS]        e.g. build/fvm/fvm "1 2 3"
#   OUTLIERS=20 CLEAN=60 bash tests/bench/discrepancy_pairs.sh  also: outliers over 20 seeds, alarms on 60 clean batches
#
# Base model per pair: 27; 15 where scale is hidden (27's linear terms absorb a scale about a shared start); the
# 9 model on a 20 mm wedge where z_coupling is hidden (27 and 15 already have pitch and roll), measured serpentine
# (on a wedge, height and time both grow along each bar: a drift and pitch and roll would be confounded); both at
# once: the 15 model's constant terms without pitch and roll (--terms), on the serpentine wedge.
set -euo pipefail
fvm="${1:-build/fvm/fvm}"
seeds="${2:-1 2 3}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
effects=(thermal_drift higher_order reference_anchor z_coupling outliers scale)

# model|terms|height for a list of hidden effects
base_of() {
  case "$1" in
    *z_coupling*scale* | *scale*z_coupling*) echo "custom|xTx:0,xTy:0,xTz:0,yTx:0,yTy:0,yTz:0,xRz:0,yRz:0,xWy:0,xWz:0,yWz:0|20|--serpentine" ;;
    *z_coupling*) echo "9||20|--serpentine" ;;
    *scale*) echo "15||0|" ;;
    *) echo "27||0|" ;;
  esac
}

run_case() {  # hidden seed -> prints "named effects|held-out before|after"
  local hidden="$1" seed="$2" base model terms height design
  base=$(base_of "$hidden")
  IFS='|' read -r model terms height design <<<"$base"
  local sim=(--seed "$seed" --stitched-frame translated --height-step-mm "$height" $design)
  local fit=()
  if [[ -n "$hidden" ]]; then sim+=(--hidden-effect "$hidden"); fi
  if [[ "$model" == custom ]]; then
    sim+=(--truth-terms "$terms")
    fit+=(--terms "$terms")
  else
    sim+=(--truth-model "$model")
    fit+=(--model "$model")
  fi
  "$fvm" simulate fvm-batch -o "$work/b" "${sim[@]}" >/dev/null
  "$fvm" diagnose "$work/b" "${fit[@]}" --json >"$work/d.json"
  jq -r '[([.effects[].effect] | join(",")), .validation.before.mean_um, .validation.after.mean_um,
          ([.effects[] | select(.effect == "outliers") | .component] | join(",")),
          ([.effects[].alternatives[]? | split(" ")[0]] | join(","))] | join("|")' "$work/d.json"
}

declare -A named_count pass_count
total=0
passed=0
passed_alt=0
printf '%-34s %4s  %-48s %9s %9s  %s\n' "hidden" "seed" "named" "before" "after" "pass"
for ((a = 0; a < ${#effects[@]}; ++a)); do
  for ((b = a + 1; b < ${#effects[@]}; ++b)); do
    pair="${effects[a]},${effects[b]}"
    for seed in $seeds; do
      IFS='|' read -r named before after _ alternatives <<<"$(run_case "$pair" "$seed")"
      ok=0 ok_alt=0
      halved=$(awk -v b="$before" -v a="$after" 'BEGIN { print (a <= 0.5 * b) }')
      if [[ $halved == 1 && ",$named," == *",${effects[a]},"* && ",$named," == *",${effects[b]},"* ]]; then ok=1; fi
      # Counting an effect the output offers as fitting the data exactly as well as a named one ("alternatives").
      offered=",$named,$alternatives,"
      if [[ $halved == 1 && "$offered" == *",${effects[a]},"* && "$offered" == *",${effects[b]},"* ]]; then ok_alt=1; fi
      total=$((total + 1))
      passed=$((passed + ok))
      passed_alt=$((passed_alt + ok_alt))
      pass_count[$pair]=$((${pass_count[$pair]:-0} + ok))
      # The diagonal counts an effect named when hidden; off it, an effect named that was not hidden, on the rows
      # of both effects that were.
      for e in $(tr ',' '\n' <<<"$named" | sort -u); do  # a case counts once, however many steps name it
        if [[ "$e" == "${effects[a]}" || "$e" == "${effects[b]}" ]]; then
          named_count[$e:$e]=$((${named_count[$e:$e]:-0} + 1))
        else
          named_count[${effects[a]}:$e]=$((${named_count[${effects[a]}:$e]:-0} + 1))
          named_count[${effects[b]}:$e]=$((${named_count[${effects[b]}:$e]:-0} + 1))
        fi
      done
      printf '%-34s %4s  %-48s %9.2f %9.2f  %s%s\n' "$pair" "$seed" "${named:-none}" "$before" "$after" "$ok" \
        "${alternatives:+  (as well: $alternatives)}"
    done
  done
done
nseeds=$(wc -w <<<"$seeds")
echo
echo "cases passed (both named, held-out gap at least halved), of $nseeds seeds:"
printf '%-18s' ""
for e in "${effects[@]:1}"; do printf ' %16s' "$e"; done
echo
for ((a = 0; a + 1 < ${#effects[@]}; ++a)); do
  printf '%-18s' "${effects[a]}"
  for ((b = 1; b < ${#effects[@]}; ++b)); do
    if ((b <= a)); then printf ' %16s' ""; else printf ' %16s' "${pass_count[${effects[a]},${effects[b]}]}"; fi
  done
  echo
done
echo "passed: $passed of $total ($(awk -v p="$passed" -v t="$total" 'BEGIN { printf "%.0f", 100 * p / t }') %)"
echo "passed, counting effects offered as fitting exactly as well: $passed_alt of $total"
echo
echo "confusion matrix, $((5 * nseeds)) cases a row (the row's effect hidden with each other one): the diagonal counts the"
echo "cases that named the row's effect; off the diagonal, the cases that named the column's effect although it was not hidden:"
columns=("${effects[@]}" frame_rotation)
printf '%-18s' "hidden \\ named"
for e in "${columns[@]}"; do printf ' %16s' "$e"; done
echo
for h in "${effects[@]}"; do
  printf '%-18s' "$h"
  for e in "${columns[@]}"; do printf ' %16s' "${named_count[$h:$e]:-0}"; done
  echo
done

if [[ -n "${OUTLIERS:-}" ]]; then
  # Truth: the outliers are the stitching-free centres that differ from the same seed's clean batch.
  missed=0 false_flags=0 count=0
  for ((seed = 1; seed <= OUTLIERS; ++seed)); do
    "$fvm" simulate fvm-batch -o "$work/clean" --seed "$seed" --stitched-frame translated >/dev/null
    IFS='|' read -r _ _ _ flagged <<<"$(run_case outliers "$seed")"
    truth=$(python3 - "$work/clean" "$work/b" <<'EOF'
import csv, sys, pathlib
def free(d):
    out = {}
    for f in sorted(pathlib.Path(d).glob("*.csv")):
        if not f.name.endswith(".free.csv"): continue
        for row in csv.reader(l for l in open(f) if not l.startswith("#")):
            if row and row[0] != "id": out[f.stem.replace(".free", "") + ":" + row[0]] = row[1:4]
    return out
a, b = free(sys.argv[1]), free(sys.argv[2])
print(",".join(k for k in b if a.get(k) != b[k]))
EOF
)
    for t in ${truth//,/ }; do
      count=$((count + 1))
      [[ ",$flagged," == *",$t,"* ]] || missed=$((missed + 1))
    done
    for f in ${flagged//,/ }; do [[ ",$truth," == *",$f,"* ]] || false_flags=$((false_flags + 1)); done
  done
  echo
  echo "outliers over $OUTLIERS seeds: $count hidden, $missed missed, $false_flags good centres flagged"
fi

if [[ -n "${CLEAN:-}" ]]; then
  alarms=0
  for ((k = 0; k < CLEAN; ++k)); do
    IFS='|' read -r named _ <<<"$(run_case "" $((100 + k)))"
    if [[ -n "$named" ]]; then alarms=$((alarms + 1)); echo "clean seed $((100 + k)): $named"; fi
  done
  echo "false alarms on $CLEAN clean batches (27 model): $alarms"
fi
