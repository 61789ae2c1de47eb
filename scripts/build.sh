#!/usr/bin/env bash
# Configures and builds Facets in ./build (Release). Extra arguments go to CMake's
# configure step, e.g. -DFACETS_WERROR=ON.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build build -j"$jobs"
