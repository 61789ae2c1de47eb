#!/usr/bin/env bash
# Every option of `facets reconstruct` is bound exactly once: each option name (a string
# literal "--name" or "--name,!--no-name" in the binding files) appears in one binding
# only, and the deleted flags in none. Exit status 1 with the offending names otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
files="apps/reconstruct_options.cc apps/reconstruct_expert_options.cc"
names=$(grep -ohE '"!?--[a-z0-9-]+(,!?--[a-z0-9-]+)*"' $files | tr -d '"!' | tr ',' '\n' | sort)
status=0
duplicates=$(echo "$names" | uniq -d)
if [ -n "$duplicates" ]; then
  echo "bound more than once:" $duplicates
  status=1
fi
for deleted in thorough-walls wall-passes polish straighten-by-kind plumb-walls plumb-gate plumb-no-corner-gate \
    normal-search-corners normal-search-support normal-search-max-here sector-regularisation; do
  if echo "$names" | grep -qx -- "--$deleted"; then
    echo "deleted flag bound: --$deleted"
    status=1
  fi
done
[ $status -eq 0 ] && echo "check-reconstruct-options: $(echo "$names" | wc -l) option names, each bound once"
exit $status
