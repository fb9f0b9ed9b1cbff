#!/usr/bin/env bash
# The README's main job: render the default synthetic stereo sequence (the rover loop, first
# 300 frames, ~75 m) and reconstruct its trajectory with `dala run`, which prints the ATE
# against the exact ground truth, and the path of its report.html (the run in 3D).
set -euo pipefail
BUILD_DIR=${1:-build}
OUT=${2:-out}
DALA="$BUILD_DIR/tools/dala"
mkdir -p "$OUT"
if [ ! -f "$OUT/rover_loop/synth.yaml" ]; then
  "$DALA" synth --preset rover_loop --frames 300 --seed 1 --out "$OUT/rover_loop"
fi
"$DALA" run "$OUT/rover_loop" --out "$OUT/rover_loop_run"
echo "[run] rendered sequence: $OUT/rover_loop/ ; reconstruction: $OUT/rover_loop_run/"
echo "[run] the run in 3D: open $OUT/rover_loop_run/report.html in a browser"
