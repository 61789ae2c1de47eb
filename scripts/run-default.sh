#!/usr/bin/env bash
# The README's main command: installs the Debian packages, builds, and runs the main
# job into ./out/default/:
#   1. render the bundled oblique block (scenes/data/block_oblique.json: 9 nadir and 12
#      oblique images of 1000 x 750 pixels over five buildings, ground pixel 0.12 m,
#      noise sigma 4) with its ground truth,
#   2. reconstruct it with `facets reconstruct` and the default scene preset (auto, which
#      chooses aerial here) down to pyramid level 1 (ground pixel 0.24 m), so that the
#      run takes a few minutes on 2 cores,
#   3. score the surface against the truth with `facets evaluate`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
scene=scenes/data/block_oblique.json
out=out/default
./build/apps/facets render "$scene" --out "$out/scene"
./build/apps/facets reconstruct --colmap "$out/scene/sparse" --images "$out/scene/images" \
  --out "$out/reconstruction" --finest-level 1
./build/apps/facets evaluate --truth "$out/scene" --mesh "$out/reconstruction/surface.ply" \
  --json "$out/evaluation.json"
echo "run-default: products in $out/reconstruction (surface.ply/.glb/.wrl, tin.ply, ortho.tif, dsm.tif," \
  "sigma.tif, preview.png, report.json, facets.log); evaluation in $out/evaluation.json"
