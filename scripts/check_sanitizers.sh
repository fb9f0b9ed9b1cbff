#!/usr/bin/env bash
# Builds dala with the sanitizers (gcc, -DDALA_SANITIZE=..., build type Sanitize: -O1 -g1, asserts
# on) and runs the whole test suite and short `dala run`s under them:
#   address  AddressSanitizer + UndefinedBehaviorSanitizer + LeakSanitizer, in build-asan/
#   thread   ThreadSanitizer (suppressions: scripts/tsan.supp), in build-tsan/
#
#   scripts/check_sanitizers.sh [address|thread|all]          (default all: address, then thread)
#
# Each mode: configure, build, ctest (unit, e2e and install tests, timeouts scaled), then
# `dala synth --preset rover_loop` and `dala run` on it in stereo and mono (60 frames), and
# `dala run` on ../shared/data/kitti06_0000-0050 (20 frames) when it exists. Every step prints
# its wall time. Environment: JOBS (compile and ctest jobs, default 2), NICENESS (default 19: the
# machine may be shared), CTEST_ARGS (extra ctest arguments, e.g. "-R MapFile").
#
# Every ASan, LSan and TSan report is written to BUILD/sanitizer/reports/<program>.<pid>
# (log_path), not to stderr: a report from a child process whose exit status a test does not look
# at is still seen, and tests that compare stderr are not disturbed. gcc 12's UBSan ignores
# log_path when it runs beside ASan and writes to stderr: the test output (ctest's LastTest.log)
# and the step logs are searched for its reports too. The reports are printed at the end. Exit
# status 1 when a step failed or any report was found, 2 on bad usage.
set -uo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
jobs=${JOBS:-2}
niceness=${NICENESS:-19}
case ${1:-all} in
  address | thread) modes=("$1") ;;
  all) modes=(address thread) ;;
  *) echo "usage: $0 [address|thread|all]" >&2; exit 2 ;;
esac

summary=()
status=0

# step NAME LOG COMMAND...: runs COMMAND niced with its output in LOG, prints the wall time.
step() {
  local name=$1 log=$2
  shift 2
  local start=$SECONDS rc
  nice -n "$niceness" "$@" > "$log" 2>&1
  rc=$?
  local line
  line=$(printf '%-8s %-18s %6d s  %s' "$mode" "$name" $((SECONDS - start)) \
         "$([ $rc -eq 0 ] && echo ok || echo "FAILED (exit $rc, log $log)")")
  echo "$line"
  summary+=("$line")
  [ $rc -eq 0 ] || status=1
  return $rc
}

for mode in "${modes[@]}"; do
  if [ "$mode" = address ]; then
    build=$root/build-asan
    timeout_scale=4
  else
    build=$root/build-tsan
    timeout_scale=10
  fi
  work=$build/sanitizer
  reports=$work/reports
  rm -rf "$work"
  mkdir -p "$reports" "$work/logs"
  logs=$work/logs

  # halt_on_error: the first report ends the process (and fails its test). ASan and TSan always
  # print the stack; UBSan only with print_stacktrace. Unknown flags would print a warning on
  # every start, so each tool gets only its own.
  export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:check_initialization_order=1:log_exe_name=1:log_path=$reports/asan"
  export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:log_exe_name=1:log_path=$reports/ubsan"
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/scripts/tsan.supp:log_exe_name=1:log_path=$reports/tsan"

  echo "== $mode: $build (reports in $reports)"
  step configure "$logs/configure.log" \
    cmake -S "$root" -B "$build" -DDALA_SANITIZE="$mode" -DCMAKE_BUILD_TYPE=Sanitize \
          -DDALA_TEST_TIMEOUT_SCALE="$timeout_scale" || continue
  step build "$logs/build.log" cmake --build "$build" -j "$jobs" || continue

  # Tests left out under TSan, each with its reason (none at the moment).
  exclude=()
  if [ "$mode" = thread ] && [ ${#exclude[@]} -gt 0 ]; then
    for e in "${exclude[@]}"; do echo "   not run under TSan: $e"; done
  fi
  ctest_exclude=()
  if [ ${#exclude[@]} -gt 0 ]; then
    pattern=$(printf '%s\n' "${exclude[@]}" | sed 's/:.*//' | paste -sd '|')
    ctest_exclude=(-E "$pattern")
  fi
  rm -f "$build/Testing/Temporary/LastTest.log"  # searched below: not one of an older run
  # shellcheck disable=SC2086  # CTEST_ARGS is a list of words
  step ctest "$logs/ctest.log" \
    ctest --test-dir "$build" -j "$jobs" --output-on-failure "${ctest_exclude[@]}" ${CTEST_ARGS:-}
  grep -E '^[0-9]+% tests passed|tests failed|^\s+[0-9]+ - ' "$logs/ctest.log" | sed 's/^/   /'

  dala=$build/tools/dala
  seq=$work/rover_loop
  if step synth "$logs/synth.log" "$dala" synth --preset rover_loop --frames 60 --out "$seq"; then
    step "run stereo" "$logs/run_stereo.log" \
      "$dala" run "$seq" --max_frames 60 --out "$work/run_stereo" --progress=false
    step "run mono" "$logs/run_mono.log" \
      "$dala" run "$seq" --max_frames 60 --mode mono --out "$work/run_mono" --progress=false
  fi
  kitti=$root/../shared/data/kitti06_0000-0050
  if [ -d "$kitti" ]; then
    step "run kitti06" "$logs/run_kitti.log" \
      "$dala" run "$kitti" --max_frames 20 --out "$work/run_kitti" --progress=false
  else
    echo "   no $kitti: the KITTI run is skipped"
  fi

  found=$(find "$reports" -type f | sort)
  if [ -n "$found" ]; then
    status=1
    line=$(printf '%-8s %d sanitizer report(s) in %s' "$mode" "$(echo "$found" | wc -l)" "$reports")
    summary+=("$line")
    echo "$line:"
    for f in $found; do
      echo "--- $f"
      head -n 60 "$f"
    done
  fi
  pattern=': runtime error: |ERROR: (Address|Leak|UndefinedBehavior)Sanitizer|WARNING: ThreadSanitizer'
  mapfile -t on_stderr < <(grep -lE "$pattern" "$build/Testing/Temporary/LastTest.log" \
                                  "$logs"/*.log 2> /dev/null)
  if [ ${#on_stderr[@]} -gt 0 ]; then
    status=1
    line=$(printf '%-8s sanitizer reports on stderr in: %s' "$mode" "${on_stderr[*]}")
    summary+=("$line")
    echo "$line:"
    grep -hE -A12 "$pattern" "${on_stderr[@]}" | head -n 200
  fi
done

echo "== summary"
printf '%s\n' "${summary[@]}"
[ $status -eq 0 ] && echo "clean" || echo "FINDINGS or failures: see above"
exit $status
