#!/usr/bin/env bash
# Fuzzes the readers of user files (fuzz/: COLMAP text model, project JSON, PLY, the
# --config file) with libFuzzer, AddressSanitizer and UndefinedBehaviorSanitizer:
#   scripts/fuzz.sh [SECONDS_PER_TARGET [TARGET...]]   (default 60 s, every target)
# Builds in ./build-sanitized (scripts/sanitized-build.sh: clang, -O1, the objects the
# sanitized unit tests use too), then runs each target for SECONDS from its seed corpus
# fuzz/corpus/<target> (new inputs go to build-sanitized/corpus/<target>, the seeds stay
# as they are). An input of at most 64 KiB that makes the reader allocate more than 1 GB
# (-malloc_limit_mb, -rss_limit_mb), run longer than 10 s, leak, or trip a sanitizer is a
# finding: its input is written to build-sanitized/artifacts/<target>/ and the script
# exits 1 after the table:
#   target        runs   exec/s  cov   features  crashes
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
targets=(fuzz_colmap fuzz_project fuzz_ply fuzz_config)
if [ $# -gt 1 ]; then targets=("${@:2}"); fi
build=build-sanitized
bash scripts/sanitized-build.sh "${targets[@]}"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/scripts/lsan.supp:print_suppressions=0}
status=0
rows=()
for target in "${targets[@]}"; do
  corpus="$build/corpus/$target"
  artifacts="$build/artifacts/$target"
  rm -rf "$artifacts"
  mkdir -p "$corpus" "$artifacts"
  log="$build/$target.log"
  set +e
  "$build/fuzz/$target" "$corpus" "fuzz/corpus/$target" -max_total_time="$seconds" -max_len=65536 \
    -rss_limit_mb=1024 -malloc_limit_mb=1024 -timeout=10 -print_final_stats=1 \
    -artifact_prefix="$artifacts/" >"$log" 2>&1
  target_status=$?
  set -e
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$log" | tail -1 | awk '{ print $2, $4 }')
  crashes=$(find "$artifacts" -type f | wc -l)
  if [ "$target_status" != 0 ]; then
    status=1
    echo "== $target: finding (exit $target_status), log $log:"
    grep -E 'ERROR|SUMMARY|runtime error|Test unit written|==[0-9]+==' "$log" | head -20
  fi
  rows+=("$(printf '%-14s %10s %8s %6s %9s %8s' "$target" "${runs:-?}" "${speed:-?}" \
    ${cov:-? ?} "$crashes")")
done
printf '%-14s %10s %8s %6s %9s %8s\n' target runs exec/s cov features crashes
printf '%s\n' "${rows[@]}"
exit "$status"
