#!/usr/bin/env bash
# The README's main job: render the default synthetic stereo sequence and evaluate it.
set -euo pipefail
BUILD_DIR=${1:-build}
OUT=${2:-out}
DALA="$BUILD_DIR/tools/dala"
mkdir -p "$OUT"
"$DALA" synth --preset rover_loop --out "$OUT/rover_loop"
echo "[run] results are in $OUT/"
