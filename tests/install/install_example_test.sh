#!/usr/bin/env bash
# Installs dala into a temporary prefix, builds docs/examples/reconstruct OUTSIDE the source tree
# against the installed package (so it can only see the installed public headers), and runs it on
# a short rendered sequence: the library API works for a user who only has `make install`.
#   install_example_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build_dir=$1
source_dir=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake --install "$build_dir" --prefix "$work/prefix" > "$work/install.log"
test -f "$work/prefix/include/dala/backend/system.h"
test -f "$work/prefix/lib/cmake/dala/dalaConfig.cmake" ||
  test -f "$work/prefix/lib64/cmake/dala/dalaConfig.cmake"

cmake -S "$source_dir/docs/examples/reconstruct" -B "$work/example" \
  -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_BUILD_TYPE=Release > "$work/configure.log"
cmake --build "$work/example" -j 2 > "$work/build.log" || { cat "$work/build.log"; exit 1; }

"$work/prefix/bin/dala" synth --out "$work/seq" --preset rover_loop --frames 25 --seed 3 \
  > /dev/null 2>&1
"$work/example/reconstruct" "$work/seq" "$work/run" | tee "$work/stdout.txt"
test "$(grep -vc '^#' "$work/run.txt")" -eq 25      # one TUM line per frame
test -s "$work/run.dmap"
grep -q "ATE RMSE" "$work/stdout.txt"
# Bad input: a clear error and exit status 2, nothing written.
if "$work/example/reconstruct" "$work/nowhere" "$work/bad" 2> "$work/err.txt"; then
  echo "expected a failure on a missing dataset"; exit 1
fi
grep -q "error:" "$work/err.txt"
test ! -e "$work/bad.txt"
echo "install + example: OK"
