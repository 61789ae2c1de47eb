#!/usr/bin/env bash
# The README's main command: installs the Debian packages, builds, and runs the main
# job on the bundled default scene (the built-up block) into ./out/.
# Until reconstruction lands, the main job renders the scene and scores the truth mesh
# against itself (it must come out with zero error and full completeness).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
scene=scenes/data/block.json
out=out/block
./build/apps/facets render "$scene" --out "$out/scene"
./build/apps/facets evaluate --truth "$out/scene" --mesh "$out/scene/truth.ply" \
  --json "$out/evaluation.json"
echo "run-default: products in $out/"
