#!/usr/bin/env bash
# The README's test command: installs the Debian packages, builds, runs every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh -DFACETS_WERROR=ON
jobs=$(nproc 2>/dev/null || echo 2)
cd build
# The log lets .ci/run repeat the count as its closing line.
ctest --output-on-failure -j"$jobs" --timeout 900 2>&1 | tee ctest.log
exit "${PIPESTATUS[0]}"
