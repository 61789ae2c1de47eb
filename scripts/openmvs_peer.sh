#!/usr/bin/env bash
# OpenMVS 2.3 (CPU) as the benchmark peer: built from source in a scratch folder, run on the
# same COLMAP model and images as Facets, never a dependency of Facets.
#
#   scripts/openmvs_peer.sh build PREFIX
#       Installs Debian's build dependencies, clones openMVS v2.3.0 and VCG (from the given
#       source URLs or local mirrors: OPENMVS_SRC, VCG_SRC), builds the tools with CUDA,
#       Python, the viewer and BreakPad off into PREFIX/bin.
#   scripts/openmvs_peer.sh run PREFIX SPARSE IMAGES OUT [--exclude-images SPEC] [--threads N]
#       Runs InterfaceCOLMAP, DensifyPointCloud, ReconstructMesh and RefineMesh (--scales 1
#       --gradient-step 25.05, as the peer meshes in ../shared/data/peers were made) and writes
#       OUT/openmvs.ply (the refined mesh) and OUT/times.tsv (wall s, CPU s, peak MB per tool).
#       Cameras that are not PINHOLE are undistorted first with COLMAP's image_undistorter
#       (OpenMVS's COLMAP importer reads only PINHOLE). --exclude-images takes Facets' syntax
#       (every-5th, every-N, a comma list of names); the held-out images and their
#       observations are removed from the model before OpenMVS sees it.
set -euo pipefail

die() { echo "openmvs_peer.sh: $*" >&2; exit 1; }
here=$(cd "$(dirname "$0")" && pwd)

build() {
  local prefix=$1
  local openmvs_src=${OPENMVS_SRC:-https://github.com/cdcseacave/openMVS.git}
  local vcg_src=${VCG_SRC:-https://github.com/cdcseacave/VCG.git}
  if [ "$(id -u)" = 0 ]; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
      cmake g++ git libboost-iostreams-dev libboost-program-options-dev libboost-system-dev \
      libboost-serialization-dev libopencv-dev libcgal-dev libeigen3-dev libglew-dev \
      libglfw3-dev libjpeg-dev libpng-dev libtiff-dev >/dev/null
  fi
  mkdir -p "$prefix"
  if [ ! -d "$prefix/vcg/vcg" ]; then
    # Only the header folders OpenMVS includes: snapshots of VCG may lack its large sample files.
    rm -rf "$prefix/vcg"
    git clone -q --no-checkout "$vcg_src" "$prefix/vcg"
    git -C "$prefix/vcg" sparse-checkout set --no-cone /vcg/ /wrap/ /eigenlib/ /img/
    git -C "$prefix/vcg" checkout -q 2>/dev/null || true
    [ -f "$prefix/vcg/vcg/complex/complex.h" ] || die "build: VCG checkout failed ($vcg_src)"
  fi
  if [ ! -d "$prefix/openMVS" ]; then
    git clone -q "$openmvs_src" "$prefix/openMVS"
    git -C "$prefix/openMVS" checkout -q v2.3.0
  fi
  cmake -S "$prefix/openMVS" -B "$prefix/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DVCG_ROOT="$prefix/vcg" -DOpenMVS_USE_CUDA=OFF -DOpenMVS_USE_PYTHON=OFF \
    -DOpenMVS_USE_OPENGL=OFF -DOpenMVS_USE_BREAKPAD=OFF -DOpenMVS_BUILD_VIEWER=OFF \
    -DCMAKE_INSTALL_PREFIX="$prefix/install" >"$prefix/configure.log"
  cmake --build "$prefix/build" -j "$(nproc)" >"$prefix/build.log"
  mkdir -p "$prefix/bin"
  for tool in InterfaceCOLMAP DensifyPointCloud ReconstructMesh RefineMesh; do
    local found
    found=$(find "$prefix/build" -type f -name "$tool" -perm -u+x | head -1)
    [ -n "$found" ] || die "build: $tool was not built (see $prefix/build.log)"
    ln -sf "$found" "$prefix/bin/$tool"
  done
  echo "OpenMVS tools in $prefix/bin"
}

# Copies a COLMAP text model without the held-out images and their observations.
exclude_images() {
  local sparse=$1 spec=$2 out=$3
  /usr/bin/python3 "$here/colmap_model_subset.py" "$sparse" "$spec" "$out"
}

# Runs one tool under /usr/bin/time -v and appends its wall s, CPU s and peak MB to times.tsv.
timed() {
  local out=$1 name=$2; shift 2
  /usr/bin/time -v -o "$out/$name.time" "$@" >"$out/$name.log" 2>&1 ||
    die "$name failed (log: $out/$name.log)"
  awk -v n="$name" -F': ' '
    /User time/ {u=$2} /System time/ {s=$2} /Maximum resident/ {m=$2}
    /Elapsed \(wall clock\)/ {k=split($2,p,":"); w=0; for(i=1;i<=k;i++) w=w*60+p[i]}
    END {printf "%s\t%.1f\t%.1f\t%.0f\n", n, w, u+s, m/1024}' "$out/$name.time" >>"$out/times.tsv"
}

run() {
  local prefix=$1 sparse=$2 images=$3 out=$4; shift 4
  local exclude="" threads=2
  while [ $# -gt 0 ]; do
    case $1 in
      --exclude-images) exclude=$2; shift 2 ;;
      --threads) threads=$2; shift 2 ;;
      *) die "run: unknown option $1" ;;
    esac
  done
  local bin=$prefix/bin
  [ -x "$bin/DensifyPointCloud" ] || die "no OpenMVS tools in $bin (run: $0 build $prefix)"
  [ -f "$sparse/cameras.txt" ] || die "$sparse: no cameras.txt (a COLMAP text model is needed)"
  [ -d "$images" ] || die "$images: no such image folder"
  mkdir -p "$out"
  out=$(cd "$out" && pwd)
  local work=$out/work
  rm -rf "$work" && mkdir -p "$work/model"
  printf "tool\twall_s\tcpu_s\tpeak_mb\n" >"$out/times.tsv"
  if [ -n "$exclude" ]; then
    exclude_images "$sparse" "$exclude" "$work/model"
  else
    cp "$sparse"/cameras.txt "$sparse"/images.txt "$sparse"/points3D.txt "$work/model/"
  fi
  local dense=$work/dense
  if grep -v '^#' "$work/model/cameras.txt" | awk 'NF {print $2}' | grep -qv '^PINHOLE$'; then
    command -v colmap >/dev/null || die "cameras are not PINHOLE and colmap is not installed"
    timed "$out" undistort colmap image_undistorter --image_path "$images" \
      --input_path "$work/model" --output_path "$dense" --output_type COLMAP
    colmap model_converter --input_path "$dense/sparse" --output_path "$dense/sparse" \
      --output_type TXT >/dev/null
  else
    mkdir -p "$dense"
    ln -s "$(cd "$images" && pwd)" "$dense/images"
    cp -r "$work/model" "$dense/sparse"
  fi
  (cd "$dense" &&
    timed "$out" InterfaceCOLMAP "$bin/InterfaceCOLMAP" -i . -o scene.mvs --image-folder images/ &&
    timed "$out" DensifyPointCloud "$bin/DensifyPointCloud" scene.mvs --max-threads "$threads" &&
    timed "$out" ReconstructMesh "$bin/ReconstructMesh" scene_dense.mvs --max-threads "$threads" &&
    timed "$out" RefineMesh "$bin/RefineMesh" scene_dense.mvs -m scene_dense_mesh.ply \
      -o scene_dense_mesh_refine.mvs --scales 1 --gradient-step 25.05 --max-threads "$threads")
  cp "$dense/scene_dense_mesh_refine.ply" "$out/openmvs.ply"
  awk -F'\t' 'NR>1 {w+=$2; c+=$3; if ($4>m) m=$4} END {
    printf "OpenMVS: %.0f s wall, %.0f CPU s, peak %.0f MB\n", w, c, m}' "$out/times.tsv"
  echo "mesh: $out/openmvs.ply"
}

case ${1:-} in
  build) [ $# -eq 2 ] || die "usage: $0 build PREFIX"; build "$2" ;;
  run) [ $# -ge 5 ] || die "usage: $0 run PREFIX SPARSE IMAGES OUT [--exclude-images SPEC]"
       shift; run "$@" ;;
  *) die "usage: $0 build PREFIX | run PREFIX SPARSE IMAGES OUT [--exclude-images SPEC]" ;;
esac
