#!/usr/bin/env bash
# Usage: scripts/colmap_tie_points.sh BLOCK_DIR [OUT_SPARSE]
#
# Tie points for a block with known poses, made the way users' are: SIFT features and
# exhaustive matching by COLMAP (CPU), triangulated with the block's poses held fixed
# (point_triangulator). BLOCK_DIR is a folder as `facets render` writes it: images/ and
# sparse/ with cameras.txt (one camera) and images.txt (known poses). The result is a
# COLMAP text model in OUT_SPARSE (default BLOCK_DIR/sparse_sift): the given cameras and
# poses with the triangulated points, outliers and uneven density included. Prints the
# point count, mean track length and mean reprojection error (pixels).
#
# Needs the colmap executable (Debian 12: apt-get install colmap, COLMAP 3.8) and python3.
# COLMAP_MAX_FEATURES: SIFT features kept per image (default 4096).
# A benchmark tool: nothing in the build or the tests depends on it.
set -euo pipefail

die() { echo "colmap_tie_points: $*" >&2; exit 1; }

[ $# -ge 1 ] && [ $# -le 2 ] || die "usage: $0 BLOCK_DIR [OUT_SPARSE]"
block=$(realpath -- "$1") || die "no such folder: $1"
out=${2:-$block/sparse_sift}
command -v colmap >/dev/null || die "colmap not found (Debian: apt-get install colmap)"
command -v python3 >/dev/null || die "python3 not found"
[ -d "$block/images" ] || die "$block/images: no image folder"
for f in cameras.txt images.txt; do
  [ -s "$block/sparse/$f" ] || die "$block/sparse/$f: missing or empty"
done

# COLMAP's GUI toolkit wants a display even for command-line runs on some builds.
export QT_QPA_PLATFORM=${QT_QPA_PLATFORM:-offscreen}

work=$(mktemp -d "${TMPDIR:-/tmp}/colmap_tie_points.XXXXXX")
trap 'rm -rf -- "$work"' EXIT
trap 'exit 130' INT TERM
log=$work/colmap.log
run() {
  echo "colmap $1" >&2
  colmap "$@" >>"$log" 2>&1 || { tail -n 30 "$log" >&2; die "colmap $1 failed (log above)"; }
}

# The one camera of cameras.txt: model and parameters as COLMAP's feature extractor takes them.
read -r model params < <(python3 - "$block/sparse/cameras.txt" <<'EOF'
import sys
path = sys.argv[1]
rows = [l.split() for l in open(path) if l.strip() and not l.startswith('#')]
if len(rows) != 1:
    sys.exit(f'{path}: {len(rows)} cameras; this script handles a block with exactly one')
r = rows[0]
if len(r) < 5:
    sys.exit(f'{path}: camera line has {len(r)} fields, expected ID MODEL WIDTH HEIGHT PARAMS...')
print(r[1], ','.join(r[4:]))
EOF
) || die "cannot read the camera of $block/sparse/cameras.txt"

# Features per image: CPU matching costs the square of it per image pair. COLMAP's default
# keeps up to 8192 (about 16,000 with the extra orientations on the rendered textures), which
# takes the better part of an hour per 21-image block on 2 cores; 4096 keeps it to minutes.
max_features=${COLMAP_MAX_FEATURES:-4096}

db=$work/database.db
run feature_extractor --database_path "$db" --image_path "$block/images" \
  --ImageReader.single_camera 1 --ImageReader.camera_model "$model" \
  --ImageReader.camera_params "$params" --SiftExtraction.use_gpu 0 \
  --SiftExtraction.max_num_features "$max_features"
run exhaustive_matcher --database_path "$db" --SiftMatching.use_gpu 0

# The known poses as an empty model whose camera and image ids are the database's (the
# triangulator looks images up by id and checks the names).
mkdir -p "$work/known"
python3 - "$db" "$block/sparse" "$work/known" <<'EOF' || die "cannot build the model of known poses"
import sqlite3, sys
db, sparse, known = sys.argv[1:4]
con = sqlite3.connect(db)
cams = con.execute('SELECT camera_id FROM cameras').fetchall()
if len(cams) != 1:
    sys.exit(f'{db}: {len(cams)} cameras after feature extraction, expected 1')
cam_id = cams[0][0]
db_ids = dict((name, i) for i, name in con.execute('SELECT image_id, name FROM images'))
cam_rows = [l.split() for l in open(f'{sparse}/cameras.txt') if l.strip() and not l.startswith('#')]
with open(f'{known}/cameras.txt', 'w') as f:
    f.write(' '.join([str(cam_id)] + cam_rows[0][1:]) + '\n')
lines = [l for l in open(f'{sparse}/images.txt') if not l.startswith('#')]
poses = lines[0::2]  # pose line, then the (ignored) 2D points line of each image
missing = []
with open(f'{known}/images.txt', 'w') as f:
    for line in poses:
        r = line.split()
        if not r:
            continue
        if len(r) < 10:
            sys.exit(f'{sparse}/images.txt: pose line has {len(r)} fields, expected 10: {line.strip()}')
        name = ' '.join(r[9:])
        if name not in db_ids:
            missing.append(name)
            continue
        f.write(' '.join([str(db_ids[name])] + r[1:8] + [str(cam_id), name]) + '\n\n')
if missing:
    sys.exit(f'{sparse}/images.txt: images not in the image folder: {", ".join(missing[:5])}')
open(f'{known}/points3D.txt', 'w').close()
EOF

mkdir -p "$work/triangulated" "$out"
run point_triangulator --database_path "$db" --image_path "$block/images" \
  --input_path "$work/known" --output_path "$work/triangulated"
run model_converter --input_path "$work/triangulated" --output_path "$out" --output_type TXT

# Figures from the written text model: points, mean track length, mean reprojection error.
python3 - "$out/points3D.txt" <<'EOF'
import sys
n = track = 0
err = 0.0
for line in open(sys.argv[1]):
    if line.startswith('#') or not line.strip():
        continue
    r = line.split()
    n += 1
    err += float(r[7])
    track += (len(r) - 8) // 2
if n == 0:
    sys.exit(f'{sys.argv[1]}: no points triangulated')
print(f'{sys.argv[1]}: {n} points, mean track length {track / n:.2f} images, '
      f'mean reprojection error {err / n:.3f} px')
EOF
