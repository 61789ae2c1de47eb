#!/usr/bin/env bash
# The README's main command: installs the Debian packages, builds, and runs the main
# job on the bundled default scene into ./out/default/:
#   1. render the seed gable-roof stereo pair (1:12000, f 153 mm, noise sigma 4) with
#      its ground truth,
#   2. reconstruct it with `facets reconstruct` (image pyramid, multigrid, start surface
#      fitted to the tie points: --start auto),
#   3. score the surface against the truth with `facets evaluate`.
# (The built-up block with walls becomes the default once walls reconstruct: issue 7.)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
scene=scenes/data/seed_gable_parallel.json
out=out/default
./build/apps/facets render "$scene" --out "$out/scene"
./build/apps/facets reconstruct --colmap "$out/scene/sparse" --images "$out/scene/images" \
  --out "$out/reconstruction" --levels 3
./build/apps/facets evaluate --truth "$out/scene" --mesh "$out/reconstruction/surface.ply" \
  --json "$out/evaluation.json"
echo "run-default: products in $out/reconstruction (surface.ply/.glb/.wrl, tin.ply, ortho.tif, dsm.tif, sigma.tif, preview.png, report.json) and $out/evaluation.json"
