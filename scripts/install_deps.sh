#!/usr/bin/env bash
# Installs dala's build dependencies from Debian packages. Idempotent: packages that are already
# installed are skipped, and apt-get is not touched at all when nothing is missing.
#   scripts/install_deps.sh          the build (make run, make build)
#   scripts/install_deps.sh --test   only what the tests need besides the build (make test): a
#                                    single-node Slurm for the bench job array test
#                                    (tests/tools/bench/slurm_bench_test.cc), opencv-doc for
#                                    its chessboard images (tests/tools/calibrate_cli_test.cc),
#                                    python3 for the check of docs/reliability.md's bounds,
#                                    chromium (and fonts-liberation, its recommended fonts,
#                                    which --no-install-recommends leaves out) for the
#                                    headless-browser test of report.html
#                                    (tests/tools/report/report_browser_test.cc)
set -euo pipefail
case "${1:-}" in
  "")
    PACKAGES=(cmake make g++ ccache pkg-config
      libceres-dev libeigen3-dev libopencv-dev libsuitesparse-dev
      libgflags-dev libgoogle-glog-dev libgtest-dev libgmock-dev libbenchmark-dev
      nlohmann-json3-dev librosbag-dev libsensor-msgs-dev)
    WHAT="packages" ;;
  --test)
    PACKAGES=(slurm-wlm munge opencv-doc python3 chromium fonts-liberation)
    WHAT="test packages" ;;
  *)
    echo "usage: $0 [--test]" >&2; exit 2 ;;
esac
missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "[deps] all ${#PACKAGES[@]} $WHAT present"
  exit 0
fi
echo "[deps] installing: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
