#!/usr/bin/env bash
# Lists every function over 80 lines and every file over 600 lines in the library and
# application folders (tests, *_test.cc, are left out), then one summary line:
#   length check: N entries (limit 10), K functions over 150, M files over 800
# Functions and their extents come from universal-ctags (a lambda counts where ctags
# reports it: inside its function, and on its own as lambda-in-FUNCTION).
# Exit status 0 (a report) unless --strict is given; with --strict, non-zero when the
# list is longer than 10 entries, a function is over 150 lines or a file over 800.
set -euo pipefail
cd "$(dirname "$0")/.."

strict=0
case "${1:-}" in
  --strict) strict=1 ;;
  "") ;;
  *) echo "usage: $0 [--strict]" >&2; exit 2 ;;
esac

DIRS=(mesh refine io visibility engine scenes apps)
FUNCTION_LINES=80 FUNCTION_MAX=150 FILE_LINES=600 FILE_MAX=800 ENTRY_LIMIT=10

if ! command -v ctags >/dev/null || ! ctags --version 2>/dev/null | grep -q "Universal Ctags"; then
  echo "check_lengths: universal-ctags is missing (bash scripts/install-deps.sh)" >&2
  exit 2
fi

# "lines path:line name", longest first.
functions=$(ctags --fields=+ne --c++-kinds=f -f - -R --languages=C++ "${DIRS[@]}" |
  awk -F'\t' -v limit="$FUNCTION_LINES" '
    $2 ~ /_test\.cc$/ { next }
    {
      start = ""; end = ""; name = $1
      for (i = 4; i <= NF; ++i) {
        if ($i ~ /^line:/) start = substr($i, 6)
        if ($i ~ /^end:/) end = substr($i, 5)
        # A lambda (ctags names it __anon...): named after the function around it.
        if (name ~ /^__anon/ && $i ~ /^function:/) name = "lambda-in-" substr($i, 10)
      }
      if (start != "" && end != "" && end - start + 1 > limit)
        printf "%d %s:%d %s\n", end - start + 1, $2, start, name
    }' | sort -k1,1nr -k2,2)

files=$(find "${DIRS[@]}" -type f \( -name '*.cc' -o -name '*.h' \) ! -name '*_test.cc' -print0 |
  xargs -0 wc -l | awk -v limit="$FILE_LINES" '$2 != "total" && $1 > limit { print $1, $2 }' |
  sort -k1,1nr -k2,2)

echo "functions over $FUNCTION_LINES lines (universal-ctags; *_test.cc left out):"
if [ -n "$functions" ]; then
  echo "$functions" | awk '{ printf "  %5d  %s  %s\n", $1, $2, $3 }'
fi
echo "files over $FILE_LINES lines in ${DIRS[*]}:"
if [ -n "$files" ]; then
  echo "$files" | awk '{ printf "  %5d  %s\n", $1, $2 }'
fi

count() { if [ -n "$1" ]; then echo "$1" | wc -l; else echo 0; fi; }
n_functions=$(count "$functions")
n_files=$(count "$files")
long_functions=$(count "$(echo "$functions" | awk -v max="$FUNCTION_MAX" 'NF && $1 > max')")
long_files=$(count "$(echo "$files" | awk -v max="$FILE_MAX" 'NF && $1 > max')")
entries=$((n_functions + n_files))
echo "length check: $entries entries (limit $ENTRY_LIMIT), $long_functions functions over" \
  "$FUNCTION_MAX, $long_files files over $FILE_MAX"

if [ "$strict" = 1 ] &&
  { [ "$entries" -gt "$ENTRY_LIMIT" ] || [ "$long_functions" -gt 0 ] || [ "$long_files" -gt 0 ]; }; then
  echo "length check failed (--strict)" >&2
  exit 1
fi
exit 0
