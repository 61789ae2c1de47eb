#!/usr/bin/env bash
# The 14 reconstruction experiments of seed 000 (Table 4.1) at lambda 2000 and 4000:
# renders each seed scene, runs `facets reconstruct` (3 pyramid levels, start plane at
# the tie points' median height, the 24 m x 24 m window) and `facets evaluate`, and
# prints a Markdown table with the seed's figures beside ours. Needs a build in ./build.
#   bash scripts/seed-experiments.sh [OUT_DIR]   (default out/seed-experiments)
#   FACETS_SEED_START=tiepoints bash scripts/seed-experiments.sh ...  (start surface, default plane)
#   FACETS_SEED_FLAGS="--normal-search" bash scripts/seed-experiments.sh ...  (more reconstruct options)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/seed-experiments}
facets=./build/apps/facets
mkdir -p "$out"

# number  scene  regularisation  seed sigma0 / rms at lambda 2000  and at 4000
rows=(
  "1 seed_cylinder_rotated_patch adaptive 4.3 0.082 4.3 0.062"
  "2 seed_cylinder_rotated_patch curvature 4.3 0.041 4.4 0.044"
  "3 seed_cylinder_rotated adaptive 4.3 0.062 4.3 0.051"
  "4 seed_cylinder_rotated curvature 4.4 0.040 4.4 0.045"
  "5 seed_cylinder_parallel adaptive 3.9 0.089 3.9 0.091"
  "6 seed_cylinder_parallel curvature 4.0 0.093 4.0 0.099"
  "7 seed_cylinder_parallel_patch adaptive 3.9 0.092 3.9 0.094"
  "8 seed_cylinder_parallel_patch curvature 4.0 0.093 4.0 0.099"
  "9 seed_gable_parallel adaptive 3.9 0.063 3.9 0.063"
  "10 seed_gable_parallel curvature 4.1 0.100 4.2 0.128"
  "11 seed_gable_rotated_patch adaptive 4.0 0.108 4.0 0.099"
  "12 seed_gable_rotated_patch curvature 4.2 0.114 4.3 0.136"
  "13 seed_gable_rotated adaptive 4.1 0.096 4.1 0.087"
  "14 seed_gable_rotated curvature 4.3 0.092 4.4 0.115"
)

echo "| exp. | scene | regularisation | lambda | sigma0 (seed) | rms dZ m (seed) | min / max dZ m | levels: iterations | sigma0 in 3.8-4.4 | rms <= seed |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for row in "${rows[@]}"; do
  read -r n scene reg s2000 r2000 s4000 r4000 <<< "$row"
  [ -d "$out/$scene/scene" ] || "$facets" render "scenes/data/$scene.json" --out "$out/$scene/scene" > /dev/null
  for lambda in 2000 4000; do
    run="$out/$scene/$reg-$lambda"
    "$facets" reconstruct --colmap "$out/$scene/scene/sparse" --images "$out/$scene/scene/images" \
      --out "$run" --levels 3 --regularisation "$reg" --lambda "$lambda" --roi -12 -12 0 12 12 9 --start "${FACETS_SEED_START:-plane}" ${FACETS_SEED_FLAGS:-} \
      --no-glb --no-vrml --no-rasters > "$run.log" 2>&1
    "$facets" evaluate --truth "$out/$scene/scene" --mesh "$run/surface.ply" > "$run.eval" 2>&1
    sigma0=$(grep -o '"sigma0_finest": [0-9.]*' "$run/report.json" | awk '{printf "%.2f", $2}')
    # Iterations of each level's summary (the per-window entries repeat them).
    iters=$(python3 -c 'import json, sys; print("/".join(str(l["summary"]["iterations"]) for l in json.load(open(sys.argv[1]))["levels"]))' "$run/report.json")
    read -r rms zmin zmax < <(grep -A1 "^Height errors" "$run.eval" | tail -1 |
      sed -E 's/.*rms ([-0-9.]+) +mean [-0-9.]+ +min ([-0-9.]+) +max ([-0-9.]+).*/\1 \2 \3/')
    if [ "$lambda" = 2000 ]; then ss=$s2000; sr=$r2000; else ss=$s4000; sr=$r4000; fi
    ok_s=$(awk -v s="$sigma0" 'BEGIN{print (s>=3.8 && s<=4.4) ? "yes" : "no"}')
    ok_r=$(awk -v r="$rms" -v t="$sr" 'BEGIN{print (r<=t) ? "yes" : "no"}')
    echo "| $n | $scene | $reg | $lambda | $sigma0 ($ss) | $rms ($sr) | $zmin / $zmax | $iters | $ok_s | $ok_r |"
  done
done
