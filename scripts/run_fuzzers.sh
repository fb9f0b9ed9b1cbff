#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz) with clang in build-fuzz/ and runs each for a bounded
# time, one after another (one process: the machine may be shared).
#
#   scripts/run_fuzzers.sh [seconds_per_target] [target...]     (default 60 s, every target)
#
# Environment: BUILD_DIR (default build-fuzz), JOBS (compile jobs, default 1), CXX (default
# clang++), NO_BUILD=1 (skip configure and build: run the targets already built, e.g. two
# invocations with different targets sharing BUILD_DIR, one per core). Each target starts from
# its seed corpus tests/fuzz/corpus/<target>/ and adds what it finds to BUILD_DIR/corpus/<target>/
# (not in the repo: copy only small, new-coverage inputs back). A crash, leak, timeout or
# out-of-memory input is written to BUILD_DIR/findings/<target>/; reproduce it with
# `BUILD_DIR/tests/fuzz/<target> FILE`. Exit status 1 when any target found one.
set -euo pipefail

seconds=${1:-60}
shift || true
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build-fuzz}
jobs=${JOBS:-1}

mkdir -p "$build"
if [ "${NO_BUILD:-0}" != 1 ]; then
  cmake -S "$root" -B "$build" -DDALA_FUZZ=ON -DCMAKE_CXX_COMPILER="${CXX:-clang++}" \
        -DCMAKE_BUILD_TYPE=Fuzz > "$build/configure.log" 2>&1 ||
    { cat "$build/configure.log"; exit 2; }
  cmake --build "$build" -j "$jobs"
fi

if [ $# -gt 0 ]; then
  targets=("$@")
else
  targets=()
  for dir in "$root"/tests/fuzz/corpus/*/; do targets+=("$(basename "$dir")"); done
fi

# Inputs larger than these are not worth the time: the seed files are a few hundred bytes.
max_len() {
  case $1 in
    map_file_fuzzer) echo 16384 ;;
    options_yaml_fuzzer | bench_suite_fuzzer) echo 8192 ;;
    *) echo 4096 ;;
  esac
}

status=0
printf '%-26s %8s %12s %s\n' target seconds executions result
for t in "${targets[@]}"; do
  corpus=$build/corpus/$t findings=$build/findings/$t log=$build/logs/$t.log
  mkdir -p "$corpus" "$findings" "$(dirname "$log")"
  # Leak checks are off: the readers hold OpenCV and glog singletons alive on purpose.
  set +e
  ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1 \
    "$build/tests/fuzz/$t" "$corpus" "$root/tests/fuzz/corpus/$t" \
      -max_total_time="$seconds" -max_len="$(max_len "$t")" -rss_limit_mb=2048 -timeout=10 \
      -print_final_stats=1 -artifact_prefix="$findings/" > "$log" 2>&1
  rc=$?
  set -e
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  crashes=$(ls "$findings")
  if [ $rc -eq 0 ] && [ -z "$crashes" ]; then
    result=ok
  else
    result="FINDING (exit $rc, log $log): $(echo "$crashes" | sed "s|^|$findings/|" | tr '\n' ' ')"
    status=1
  fi
  printf '%-26s %8s %12s %s\n' "$t" "$seconds" "${execs:-?}" "$result"
done
exit $status
