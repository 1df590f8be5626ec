#!/usr/bin/env bash
# Runs the whole test suite: installs what is missing, builds (Release), runs CTest.
#   scripts/test.sh              the suite (what CI runs)
#   scripts/test.sh --sanitize   also an AddressSanitizer + UndefinedBehaviorSanitizer build in
#                                build-sanitize/ (the library and the tools instrumented, the tests
#                                linked with the sanitizers' runtime) running every test but the
#                                slow-labelled renders,
#                                and, where clang++ is installed, a fuzzing smoke run of every
#                                reader (scripts/fuzz.sh, DPS_FUZZ_SECONDS each, default 60; 0 = none)
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${DPS_BUILD_DIR:-$ROOT/build}
JOBS=$(nproc 2>/dev/null || echo 2)
"$ROOT/scripts/build.sh"
(cd "$BUILD_DIR" && ctest --output-on-failure -j "$JOBS")
if [ "${1:-}" = "--sanitize" ]; then
  SAN_DIR=${DPS_SANITIZE_BUILD_DIR:-$ROOT/build-sanitize}
  # -O1 -g1: half the compile time of -O2 -g under the sanitizers (the build is most of CI's time),
  # still optimised enough for the tests and with line numbers in the reports.
  cmake -S "$ROOT" -B "$SAN_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
    -DDPS_SANITIZE=ON -DDPS_BUILD_BENCHMARKS=OFF >/dev/null
  cmake --build "$SAN_DIR" -j "$JOBS"
  # Leaks are not errors (OpenCV's backends keep caches); any other report fails the test.
  export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  (cd "$SAN_DIR" && ctest --output-on-failure -j "$JOBS" -LE slow)
  if [ "${DPS_FUZZ_SECONDS:-60}" = 0 ]; then
    echo "test.sh: DPS_FUZZ_SECONDS=0: no fuzzing smoke run" >&2
  elif command -v clang++ >/dev/null 2>&1; then
    "$ROOT/scripts/fuzz.sh" "${DPS_FUZZ_SECONDS:-60}"
  else
    echo "test.sh: clang++ not installed: no fuzzing smoke run (scripts/fuzz.sh needs it)" >&2
  fi
fi
