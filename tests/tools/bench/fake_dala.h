#ifndef DALA_TESTS_TOOLS_BENCH_FAKE_DALA_H_
#define DALA_TESTS_TOOLS_BENCH_FAKE_DALA_H_

// A fake `dala` executable for the `dala bench` tests (bash + awk), implementing the contracts
// of `dala synth` and `dala run` minimally:
//  - synth --out DIR [--frames N] [--seed S] [--preset P]: a KITTI-like folder (times.txt,
//    poses.txt, calib.txt, synth.yaml) whose path is a 40 m square, 2 m per frame (20 frames a
//    side), identity orientations. Each call appends a line to DIR/../../synth_calls.txt.
//    --preset broken: exit 2 with a message.
//  - run SEQ --out RUNDIR --estimator E --mode M [--first_frame F] [--set k=v]...:
//    trajectory.txt (TUM) = ground truth of frames F.. with a known error, report.json with
//    per-frame times 10 + (i % 10) ms, a placeholder report.html; appends "run E M F" to RUNDIR/../../../run_calls.txt.
//      stereo: z offset d * (+1, -1, -1, +1, ...) by frame index, d = 0.1 + 0.01 F m. Over blocks
//        of 4 frames on one side of the square this offset is orthogonal to the path (sum s_i = 0
//        and sum s_i p_i = 0), so for F a multiple of 4 the SE(3) alignment is the identity and
//        every ATE error is exactly d.
//      --set fake.seed_error=1: d grows by 0.05 m per seed above 1 (the seed in SEQ/synth.yaml),
//        so that the seeds of a rendered preset give different ATEs.
//      mono: positions doubled: Sim(3) aligns them exactly (ATE 0, scale 0.5).
//    --set fake.fail=1: exit 1 with a message; fake.fail_start=F: the same when started at F;
//    fake.crash=1: kill -SEGV itself;
//    fake.sleep=S: sleep S seconds first; ba with mono: exit 2 "... is not supported".

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "tests/test_util.h"

namespace dala::testing {

inline const char* kFakeDalaScript = R"SCRIPT(#!/bin/bash
cmd=$1; shift
if [ "$cmd" = synth ]; then
  frames=80; seed=1; out=""; preset=""
  while [ $# -gt 0 ]; do
    case $1 in --out) out=$2; shift;; --frames) frames=$2; shift;; --seed) seed=$2; shift;;
      --preset) preset=$2; shift;; --mono) ;; esac; shift
  done
  echo "synth $preset" >> "$(dirname "$out")/../synth_calls.txt"
  if [ "$preset" = broken ]; then echo "dala synth: error: unknown preset 'broken'" >&2; exit 2; fi
  mkdir -p "$out"
  awk -v n=$frames 'BEGIN { for (i = 0; i < n; i++) printf "%.6f\n", i * 0.1 }' > "$out/times.txt"
  awk -v n=$frames 'BEGIN { for (i = 0; i < n; i++) { s = int(i / 20) % 4; j = i % 20;
      if (s == 0) { x = 2 * j; y = 0 } else if (s == 1) { x = 40; y = 2 * j }
      else if (s == 2) { x = 40 - 2 * j; y = 40 } else { x = 0; y = 40 - 2 * j }
      printf "1 0 0 %.6f 0 1 0 %.6f 0 0 1 0\n", x, y } }' > "$out/poses.txt"
  printf 'P0: 450 0 376 0 0 450 240 0 0 0 1 0\nP1: 450 0 376 -180 0 450 240 0 0 0 1 0\n' > "$out/calib.txt"
  printf '%%YAML:1.0\nformat: dala-synthetic\nversion: 1\npreset: %s\nseed: %s\n' "$preset" "$seed" > "$out/synth.yaml"
  exit 0
fi
[ "$cmd" = run ] || { echo "fake dala: unknown command $cmd" >&2; exit 2; }
seq=$1; shift
out=""; est=""; mode=""; fail=0; crash=0; sleep_s=0; first=0; fail_start=-1; seed_error=0
while [ $# -gt 0 ]; do
  case $1 in --out) out=$2; shift;; --estimator) est=$2; shift;; --mode) mode=$2; shift;;
    --first_frame) first=$2; shift;;
    --set) case $2 in fake.fail=1) fail=1;; fake.crash=1) crash=1;;
                      fake.fail_start=*) fail_start=${2#fake.fail_start=};;
                      fake.seed_error=1) seed_error=1;;
                      fake.sleep=*) sleep_s=${2#fake.sleep=};; esac; shift;;
  esac; shift
done
echo "run $est $mode $first" >> "$out/../../../run_calls.txt"
[ "$first" = "$fail_start" ] && fail=1
seed=$(awk '/^seed:/ { print $2 }' "$seq/synth.yaml" 2>/dev/null); seed=${seed:-1}
echo "fake dala run: $est $mode on $seq"
if [ $fail = 1 ]; then echo "error: the fake estimator diverged" >&2; exit 1; fi
if [ $crash = 1 ]; then kill -SEGV $$; fi
if [ "$sleep_s" != 0 ]; then sleep "$sleep_s"; fi
if [ "$est" = ba ] && [ "$mode" = mono ]; then
  echo "dala run: error: --estimator ba with --mode mono is not supported" >&2; exit 2
fi
d=$(awk -v f=$first -v s=$seed -v e=$seed_error 'BEGIN { printf "%.6f", 0.1 + 0.01 * f + (e ? 0.05 * (s - 1) : 0) }')
paste -d' ' "$seq/times.txt" "$seq/poses.txt" | awk -v mono=$([ "$mode" = mono ] && echo 1 || echo 0) -v first=$first -v d=$d 'NR > first {
  i = NR - 1; k = i % 4; s = (k == 0 || k == 3) ? 1 : -1;
  if (mono) printf "%s %.6f %.6f %.6f 0 0 0 1\n", $1, 2 * $5, 2 * $9, 2 * $13;
  else printf "%s %.6f %.6f %.6f 0 0 0 1\n", $1, $5, $9, $13 + d * s }' > "$out/trajectory.txt.tmp"
mv "$out/trajectory.txt.tmp" "$out/trajectory.txt"
n=$(( $(wc -l < "$seq/times.txt") - first ))
awk -v n=$n -v est=$est -v mode=$mode 'BEGIN {
  printf "{\"dataset\": {\"path\": \"x\", \"format\": \"synthetic\", \"frames\": %d, \"stereo\": true},\n", n
  printf " \"estimator\": \"%s\", \"mode\": \"%s\", \"options\": {},\n \"frames\": [", est, mode
  for (i = 0; i < n; i++) { t = 10 + i % 10;
    printf "%s{\"frame\": %d, \"t\": %.1f, \"status\": \"%s\", \"keyframe\": %s, \"features\": 500, \"landmarks\": 100, \"ms\": {\"frontend\": %.1f, \"estimator\": %.1f, \"total\": %.1f}}", (i ? ",\n  " : ""), i, i * 0.1, (i == 5 ? "lost" : "tracking"), (i % 5 == 0 ? "true" : "false"), t * 0.6, t * 0.4, t }
  printf "],\n \"summary\": {\"frames\": %d, \"fps\": 70.0, \"tracking_failures\": 1, \"keyframes\": 16, \"keyframes_in_map\": 12, \"disparity_offset_px\": 0.25, \"landmarks\": 4321, \"pairs\": %d}}\n", n, n }' > "$out/report.json.tmp"
mv "$out/report.json.tmp" "$out/report.json"
printf '<!DOCTYPE html><title>fake run report</title>\n' > "$out/report.html"
exit 0
)SCRIPT";

// Expects a merged bench output folder to equal a one-machine one: results.json but for what
// differs between two executions of the same run (times, memory, the absolute paths in commands
// and errors) and the merge's provenance; summary.csv and the per-run ATE section of results.md
// byte for byte (no time or path in them).
inline void ExpectSameBenchResults(const std::string& whole, const std::string& merged) {
  nlohmann::json a = nlohmann::json::parse(ReadAll(whole + "/results.json"));
  nlohmann::json b = nlohmann::json::parse(ReadAll(merged + "/results.json"));
  for (nlohmann::json* j : {&a, &b}) {
    for (const char* key : {"merged_from", "suite"}) j->erase(key);
    for (auto& run : (*j)["runs"]) {
      for (const char* key : {"wall_s", "peak_rss_mb", "command", "error"}) run.erase(key);
    }
  }
  EXPECT_EQ(a.dump(1), b.dump(1));
  EXPECT_EQ(ReadAll(whole + "/summary.csv"), ReadAll(merged + "/summary.csv"));
  const auto section = [](const std::string& md) {
    const size_t from = md.find("## ATE RMSE over the runs");
    return md.substr(from, md.find("## ATE RMSE [m], median") - from);
  };
  EXPECT_EQ(section(ReadAll(whole + "/results.md")), section(ReadAll(merged + "/results.md")));
}

}  // namespace dala::testing

#endif  // DALA_TESTS_TOOLS_BENCH_FAKE_DALA_H_
