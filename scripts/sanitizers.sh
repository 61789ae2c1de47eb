#!/usr/bin/env bash
# The unit tests (`ctest -L unit`) under AddressSanitizer (with LeakSanitizer) and
# UndefinedBehaviorSanitizer: any report fails its test.
#   scripts/sanitizers.sh [TEST_TARGET...]
# Builds the given unit-test executables (default facets_unit_tests: all of them, e.g.
# facets_io_tests facets_mesh_tests for a subset) in ./build-sanitized
# (scripts/sanitized-build.sh: clang, -O1, the objects scripts/fuzz.sh links too), runs
# the unit tests of every executable built there and prints
# "sanitizers: N tests, build S s, tests S s" at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
build=build-sanitized
start=$(date +%s)
bash scripts/sanitized-build.sh "${@:-facets_unit_tests}"
built=$(date +%s)
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:detect_stack_use_after_return=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/scripts/lsan.supp:print_suppressions=0}
cd "$build"
set +e
# Executables not built (a subset) stand in ctest as *_NOT_BUILT placeholders.
ctest --output-on-failure -j"$(nproc 2>/dev/null || echo 2)" -L '^unit$' -E '_NOT_BUILT$' --no-tests=error 2>&1 |
  tee ctest-sanitizers.log
status=${PIPESTATUS[0]}
set -e
tests=$(grep -E '^[0-9]+% tests passed' ctest-sanitizers.log | tail -1 | sed -E 's/.* out of ([0-9]+).*/\1/')
echo "sanitizers: ${tests:-0} tests, build $((built - start)) s, tests $(($(date +%s) - built)) s"
exit "$status"
