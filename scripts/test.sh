#!/usr/bin/env bash
# Runs the whole test suite: installs what is missing, builds (Release), runs CTest.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${DPS_BUILD_DIR:-$ROOT/build}
"$ROOT/scripts/build.sh"
cd "$BUILD_DIR"
ctest --output-on-failure -j "$(nproc 2>/dev/null || echo 2)"
