#!/usr/bin/env bash
# Installs every Debian 12 package Facets needs to build, test and validate its
# products. Safe to run again; needs root (or sudo).
set -euo pipefail
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libcgal-dev libgmp-dev libmpfr-dev       # Delaunay start grid
  libembree-dev                            # ray casting
  libeigen3-dev                            # linear algebra, sparse
  libopenmesh-dev                          # half-edge TIN
  libtinygltf-dev                          # glTF
  libopenimageio-dev openimageio-tools     # images
  libgtest-dev libgmock-dev                # tests
  libtbb-dev                               # threads
  nlohmann-json3-dev                       # project files, scenes, reports
  libcli11-dev                             # command line of the facets binary
  view3dscene                              # tovrmlx3d: reads the .wrl products (validate-products.sh)
  libgdal-dev                              # GeoTIFF orthophoto and DSM (io/raster_io)
  libtiff-dev                              # damaged deflate TIFF strips (io/tiff_strips)
  universal-ctags                          # function extents for scripts/check_lengths.sh
  clang libclang-rt-14-dev                 # libFuzzer and its sanitizers (scripts/fuzz.sh)
)

export DEBIAN_FRONTEND=noninteractive
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# node + npm run the Khronos glTF validator (scripts/validate-products.sh). Only when
# absent: a machine may have them from elsewhere (e.g. NodeSource's nodejs, which
# conflicts with Debian's npm package).
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then missing+=(nodejs npm); fi
if [ ${#missing[@]} -gt 0 ]; then
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
# The OpenImageIO CMake target of Debian 12 lists /usr/include/opencv4 as an include
# directory; CMake refuses a missing one. The top-level CMakeLists strips it, so no
# OpenCV is needed here.
echo "install-deps: all packages present"
