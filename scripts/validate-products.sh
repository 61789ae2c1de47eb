#!/usr/bin/env bash
# Validates Facets' export products with real readers:
#   .glb  Khronos glTF validator (npm package gltf-validator, run by node): fails on any
#         error or warning (infos and hints are printed, not failures).
#   .wrl  tovrmlx3d (Debian package view3dscene) converts the file to X3D; it exits 0
#         even on errors, so any output on stderr is a failure.
#
# Usage:
#   scripts/validate-products.sh [--build DIR] [FILE_OR_FOLDER ...]
# With files or folders: validates those (folders: every .glb and .wrl inside).
# Without: builds the export tests in DIR (default: ./build, configured if needed), runs
# them with FACETS_PRODUCTS_DIR=DIR/products (they write the products of bundled scenes,
# synthetic meshes and a small reconstructed run, as `facets reconstruct` wrote them and
# as `facets export` re-wrote them) and validates every file in that folder.
#
# The validator is installed by npm into DIR/node_tools (gitignored; the npm registry
# is the only non-Debian download). tovrmlx3d and node/npm come from
# scripts/install-deps.sh. Exit status: 0 all valid, 1 a product failed, 2 tooling
# or usage problem.
set -euo pipefail
root=$(realpath "$(dirname "$0")/..")

# Paths on the command line are relative to the caller's folder.
build="$root/build"
inputs=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) [ $# -ge 2 ] || { echo "validate-products: --build needs a folder" >&2; exit 2; }
             build=$(realpath -m "$2"); shift 2 ;;
    -h|--help) sed -n '2,19p' "$0"; exit 0 ;;
    *) inputs+=("$(realpath -m "$1")"); shift ;;
  esac
done
cd "$root"

die() { echo "validate-products: $*" >&2; exit 2; }

GLTF_VALIDATOR_VERSION=2.0.0-dev.3.10
tools="$build/node_tools"

command -v node >/dev/null || die "node not found (scripts/install-deps.sh installs nodejs)"
command -v npm >/dev/null || die "npm not found (scripts/install-deps.sh installs npm)"
command -v tovrmlx3d >/dev/null || die "tovrmlx3d not found (scripts/install-deps.sh installs view3dscene)"

if [ ${#inputs[@]} -eq 0 ]; then
  products="$build/products"
  if [ ! -f "$build/build.ninja" ] && [ ! -f "$build/Makefile" ]; then
    cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null ||
      die "cannot configure $build"
  fi
  targets=(facets_export_tests)
  # Bundled scenes' truth meshes; and a small `facets reconstruct` run with its
  # products re-written by `facets export` (both copies are validated).
  for t in facets_export_products_tests facets_export_cli_tests; do
    if grep -q "$t" "$root/tests/CMakeLists.txt" 2>/dev/null; then targets+=("$t"); fi
  done
  cmake --build "$build" --target "${targets[@]}" -j"$(nproc 2>/dev/null || echo 2)" >/dev/null ||
    die "cannot build ${targets[*]} in $build"
  rm -rf "$products"
  mkdir -p "$products"
  for t in "${targets[@]}"; do
    exe=$(find "$build" -type f -name "$t" -perm -u+x | head -n 1)
    [ -n "$exe" ] || die "test executable $t not found in $build"
    echo "validate-products: writing products with $t"
    FACETS_PRODUCTS_DIR="$products" "$exe" --gtest_brief=1 >/dev/null ||
      die "$t failed (run it directly to see why)"
  done
  inputs=("$products")
fi

files=()
for input in "${inputs[@]}"; do
  if [ -d "$input" ]; then
    while IFS= read -r -d '' f; do files+=("$f"); done \
      < <(find "$input" -type f \( -name '*.glb' -o -name '*.wrl' \) -print0 | sort -z)
  elif [ -f "$input" ]; then
    files+=("$input")
  else
    die "no such file or folder: $input"
  fi
done
glbs=()
wrls=()
for f in "${files[@]}"; do
  case "$f" in
    *.glb) glbs+=("$f") ;;
    *.wrl) wrls+=("$f") ;;
    *) die "not a .glb or .wrl file: $f" ;;
  esac
done
[ ${#files[@]} -gt 0 ] || die "no .glb or .wrl files to validate in ${inputs[*]}"

failed=0

if [ ${#glbs[@]} -gt 0 ]; then
  if [ ! -f "$tools/node_modules/gltf-validator/package.json" ] ||
     ! grep -q "\"version\": \"$GLTF_VALIDATOR_VERSION\"" "$tools/node_modules/gltf-validator/package.json"; then
    mkdir -p "$tools"
    echo "validate-products: npm install gltf-validator@$GLTF_VALIDATOR_VERSION into $tools"
    npm install --prefix "$tools" --no-audit --no-fund --loglevel=error \
      "gltf-validator@$GLTF_VALIDATOR_VERSION" >/dev/null || die "npm install gltf-validator failed"
  fi
  # The validator reports issues by severity: 0 error, 1 warning, 2 info, 3 hint.
  NODE_PATH="$tools/node_modules" node - "${glbs[@]}" <<'JS' || failed=1
const fs = require('fs');
const validator = require('gltf-validator');
(async () => {
  let bad = 0;
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)),
                                                 {uri: file, maxIssues: 0});
    const i = report.issues;
    const ok = i.numErrors === 0 && i.numWarnings === 0;
    console.log(`${ok ? 'OK  ' : 'FAIL'} glb ${file}: ${i.numErrors} errors, ` +
                `${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints` +
                ` (${report.info ? report.info.totalTriangleCount : '?'} triangles)`);
    const shown = new Set();
    for (const m of i.messages) {
      const key = `${m.severity} ${m.code}`;
      if (shown.has(key)) continue;
      shown.add(key);
      const level = ['error', 'warning', 'info', 'hint'][m.severity];
      console.log(`       ${level} ${m.code}: ${m.message} (${m.pointer || m.offset || ''})`);
    }
    if (!ok) bad++;
  }
  process.exit(bad ? 1 : 0);
})().catch((e) => { console.error(`validate-products: glTF validator: ${e}`); process.exit(2); });
JS
fi

# tovrmlx3d is lenient: it reads a truncated file without a message and does not load
# textures. So also check the header, balanced braces/brackets (outside strings and
# comments) and that every url names a file beside the .wrl.
wrl_structure() {
  local f=$1 dir
  dir=$(dirname "$f")
  [ "$(head -n 1 "$f")" = "#VRML V2.0 utf8" ] || echo "first line is not '#VRML V2.0 utf8'"
  awk '{ sub(/"[^"]*"/, ""); sub(/#.*/, "");
         b += gsub(/\{/, "{"); b -= gsub(/\}/, "}");
         s += gsub(/\[/, "["); s -= gsub(/\]/, "]") }
       END { if (b != 0) print "unbalanced braces ({ minus }: " b ")";
             if (s != 0) print "unbalanced brackets ([ minus ]: " s ")" }' "$f"
  { grep -o 'url "[^"]*"' "$f" || true; } | sed 's/^url "//; s/"$//' | while IFS= read -r url; do
    [ -s "$dir/$url" ] || echo "texture url \"$url\" names no file beside the .wrl"
  done
}

for f in "${wrls[@]}"; do
  err=$(mktemp)
  structure=$(wrl_structure "$f") || structure="cannot check the file's structure"
  if ! tovrmlx3d "$f" >/dev/null 2>"$err"; then
    echo "FAIL wrl $f: tovrmlx3d exited with an error"
    failed=1
  elif [ -s "$err" ]; then
    echo "FAIL wrl $f: tovrmlx3d reported:"
    failed=1
  elif [ -n "$structure" ]; then
    echo "FAIL wrl $f: read by tovrmlx3d, but:"
    failed=1
  else
    echo "OK   wrl $f: read by tovrmlx3d without messages"
  fi
  sed 's/^/       /' "$err"
  [ -z "$structure" ] || echo "$structure" | sed 's/^/       /'
  rm -f "$err"
done

if [ "$failed" != 0 ]; then
  echo "validate-products: FAILED (${#glbs[@]} glb, ${#wrls[@]} wrl checked)" >&2
  exit 1
fi
echo "validate-products: all ${#glbs[@]} glb and ${#wrls[@]} wrl files valid"
