#!/usr/bin/env bash
# Fuzzes every file reader of fvm with libFuzzer, AddressSanitizer and UBSan (Debian's clang 14).
#
#   tests/fuzz/run.sh [EXECUTIONS]      default 20000 inputs per reader; CI runs 2000 per reader after the
#                                       regression inputs (bash run.sh test). The documented run behind the
#                                       closing notes is tests/fuzz/run.sh 100000 (one to two hours on 2 cores:
#                                       the image, layout and batch readers are the slow ones).
#
# Configures build-fuzz/ (clang, Ninja, -DFVM_FUZZ=ON; set FVM_FUZZ_BUILD for another directory), builds only the
# fuzz targets, replays the regression inputs of each reader (tests/fuzz/regressions/<reader>/), then runs it for
# EXECUTIONS inputs starting from its seed corpus (tests/fuzz/corpus/<reader>/; new inputs it finds go to
# build-fuzz/fuzz-corpus/<reader>/, never into the source tree). Exits non-zero on any crash, sanitizer report,
# leak, timeout (10 s per input) or out-of-memory (2 GB), with the input saved as
# build-fuzz/fuzz-findings/<reader>/<kind>-<hash>.
#
# Longer runs: a larger count (tests/fuzz/run.sh 1000000), or one reader for a fixed time on both cores:
#   build-fuzz/tests/fuzz/pcd_fuzz -max_total_time=3600 -jobs=2 build-fuzz/fuzz-corpus/pcd tests/fuzz/corpus/pcd
# Reproduce a finding: build-fuzz/tests/fuzz/<reader>_fuzz FILE. Keep it as tests/fuzz/regressions/<reader>/NAME
# once fixed. Only some readers: FVM_FUZZ_READERS="pcd ply" tests/fuzz/run.sh
set -euo pipefail

executions=${1:-20000}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=${FVM_FUZZ_BUILD:-$root/build-fuzz}
fuzz_dir=$root/tests/fuzz

# -O1: the usual trade for fuzzing, fast enough to run and far quicker to build under the sanitizers.
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFVM_PYTHON=OFF -DCMAKE_C_COMPILER=clang-14 \
  -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DFVM_FUZZ=ON >/dev/null
cmake --build "$build" --target fuzz_targets

readers=${FVM_FUZZ_READERS:-$(cd "$build/tests/fuzz" && ls -- *_fuzz | sed 's/_fuzz$//')}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
failed=()
for reader in $readers; do
  target=$build/tests/fuzz/${reader}_fuzz
  findings=$build/fuzz-findings/$reader
  corpus=$build/fuzz-corpus/$reader
  mkdir -p "$findings" "$corpus"
  # -seed=1: the same mutations on every run, so CI is reproducible; a longer run may pass another seed.
  options=(-seed=1 -timeout=10 -rss_limit_mb=2048 -artifact_prefix="$findings/" -print_final_stats=1)
  runs=$executions
  leak_options=()
  case $reader in
    height_map_image | tile_image | lext)
      # OpenImageIO's PNG reader leaks by design (PNGInput::PngReadCallback formats an error into a std::string,
      # then libpng longjmps past its destructor); only the slow unwinder (12 inputs/s) could suppress that leak
      # by name, so leaks are not checked for these two readers. Crashes, overflows and UB still are.
      leak_options=(env ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0")
      # OpenImageIO 2.4 reserves a buffer of RowsPerStrip scanlines from the TIFF header before it reads a strip
      # (2.2 GB for regressions/height_map_image/tiff-declares-2gb.tif) and never touches it: fvm info on that
      # file peaks at 137 MB resident. libFuzzer would call the reservation itself an out-of-memory, so single
      # allocations may reach 4 GB here; what is used is still held to the 2 GB resident limit.
      options+=(-malloc_limit_mb=4096)
      ;;
    datx)
      # The DATX reader's HDF5 child runs under a memory cap (RLIMIT_AS): an allocation beyond it must fail as it
      # does in a release build (HDF5 reports it, fvm refuses the file naming the cap), not end the child. Every
      # execution forks, and a fork copies the fuzzer's page tables: ASan's quarantine of freed memory (256 MB by
      # default) grew the fuzzer to 200 MB and made the forks two thirds of the time; 32 MB still holds the reader's
      # own frees of an execution (a few MB) for use-after-free checks.
      leak_options=(env ASAN_OPTIONS="$ASAN_OPTIONS:allocator_may_return_null=1:quarantine_size_mb=32")
      ;;
  esac
  if [[ -d $fuzz_dir/regressions/$reader ]]; then
    echo "== $reader: regression inputs"
    if ! "${leak_options[@]}" "$target" "${options[@]}" "$fuzz_dir"/regressions/"$reader"/*; then
      failed+=("$reader (a regression input)")
    fi
  fi
  seeds=()
  [[ -d $fuzz_dir/corpus/$reader ]] && seeds=("$fuzz_dir/corpus/$reader")
  echo "== $reader: $runs executions"
  start=$(date +%s)
  if ! "${leak_options[@]}" "$target" "${options[@]}" -runs="$runs" "$corpus" "${seeds[@]}" 2>"$build/fuzz-findings/$reader.log"; then
    tail -n 40 "$build/fuzz-findings/$reader.log"
    failed+=("$reader")
  fi
  grep -E '^stat::number_of_executed_units|^stat::peak_rss_mb' "$build/fuzz-findings/$reader.log" | tr '\n' ' ' || true
  echo "($(($(date +%s) - start)) s)"
done

if ((${#failed[@]})); then
  echo "fuzzing found problems in: ${failed[*]} (inputs in $build/fuzz-findings/)" >&2
  exit 1
fi
echo "fuzzing: no findings in $executions executions per reader"
