#!/usr/bin/env bash
# The README's test command: installs the Debian packages, builds, runs every test:
# the `unit` label first (module tests, seconds each), then `e2e` (rendered scenes
# reconstructed, minutes each), each timed:
#   label unit: N tests, S s
# Tests that need the real data sets (FACETS_SHARED_DATA, default ../shared/data) skip
# when they are absent; ctest names them under "The following tests did not run".
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh -DFACETS_WERROR=ON
jobs=$(nproc 2>/dev/null || echo 2)
cd build
# ctest.log holds both labels' output (one ctest summary line each): .ci/run adds them up
# for its closing line.
: >ctest.log
status=0
for label in unit e2e; do
  start=$(date +%s.%N)
  set +e
  # Per-test timeouts are test properties (cmake/FacetsHelpers.cmake): 120 s unit, 900 s e2e.
  ctest --output-on-failure -j"$jobs" -L "^${label}\$" --no-tests=error 2>&1 | tee "ctest-$label.log"
  label_status=${PIPESTATUS[0]}
  set -e
  seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.0f", b - a }')
  tests=$(grep -E '^[0-9]+% tests passed, [0-9]+ tests failed out of [0-9]+' "ctest-$label.log" |
    tail -1 | sed -E 's/.* out of ([0-9]+).*/\1/' || true)
  cat "ctest-$label.log" >>ctest.log
  echo "label $label: ${tests:-0} tests, $seconds s" | tee -a ctest.log
  if [ "$label_status" != 0 ]; then status=$label_status; fi
done
exit "$status"
