#!/usr/bin/env bash
# One sanitized build for both scripts/sanitizers.sh (the unit tests) and scripts/fuzz.sh
# (the fuzz targets), so CI compiles the engine once for the two:
#   scripts/sanitized-build.sh TARGET...
# Configures ./build-sanitized on its first use: clang, -DFACETS_FUZZ=ON (every object with
# AddressSanitizer, UndefinedBehaviorSanitizer and libFuzzer's coverage instrumentation,
# line tables for the reports' stack traces), -O1, ccache when present; then builds the
# targets, one build at a time on a shared machine (the lock of the other builds).
set -euo pipefail
cd "$(dirname "$0")/.."
build=build-sanitized
if [ ! -f "$build/build.ninja" ]; then
  launcher=()
  if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -DNDEBUG" -DFACETS_FUZZ=ON "${launcher[@]}" >/dev/null
fi
flock /tmp/facets-build.lock cmake --build "$build" -j"$(nproc 2>/dev/null || echo 2)" --target "$@"
