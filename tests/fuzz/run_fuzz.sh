#!/bin/sh
# Builds the libFuzzer targets (clang, -fsanitize=fuzzer,address,undefined) in build-fuzz/ and runs
# each for a bounded time from its seed corpus. Needs Debian's clang and libclang-rt-14-dev
# (sh tests/fuzz/install-fuzz-deps). Usage: tests/fuzz/run_fuzz.sh [SECONDS_PER_TARGET] [TARGET...]
# New crashing inputs land in build-fuzz/findings/TARGET/; copy them to tests/fuzz/regressions/
# (case, measurements, mesh) and the regression tests (tests/test_bad_input.cpp) replay them.
set -e
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build="$root/build-fuzz"
seconds=${1:-60}
[ $# -gt 0 ] && shift
targets=${*:-fuzz_case fuzz_measurements fuzz_mesh}
if [ ! -f "$build/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ cmake -S "$root" -B "$build" -DDEMDESIGN_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" >/dev/null
fi
cmake --build "$build" -j"${JOBS:-1}" --target $targets
status=0
for target in $targets; do
  kind=${target#fuzz_}
  corpus="$build/corpus/$kind"
  findings="$build/findings/$target"
  mkdir -p "$corpus" "$findings"
  # Seeds: the shipped cases, a measurement file, small meshes (first byte picks the extension).
  case $kind in
    case) cp "$root"/cases/*.yaml "$corpus/" ;;
    *) cp "$here/seeds/$kind"/* "$corpus/" ;;
  esac
  # Kept crashing inputs are seeds too (a folder only where some were found: git keeps no empty one).
  regressions=""
  [ -d "$root/tests/fuzz/regressions/$kind" ] && regressions="$root/tests/fuzz/regressions/$kind"
  echo "== $target: $seconds s from $(ls "$corpus" | wc -l) inputs"
  # -rss_limit_mb / -malloc_limit_mb: allocating without bound is a finding; -timeout: so is a hang.
  ASAN_OPTIONS=detect_leaks=0:allocator_may_return_null=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  OMP_NUM_THREADS=1 DEMDESIGN_MATERIALS="$root/materials" \
    "$build/tests/fuzz/$target" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 -malloc_limit_mb=1024 \
      -max_len=16384 -artifact_prefix="$findings/" -print_final_stats=1 "$corpus" \
      $regressions 2>"$build/$target.log" || status=1
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb|^Done|ERROR|SUMMARY" "$build/$target.log" | head -8 || true
  ls "$findings" | head
done
exit $status
