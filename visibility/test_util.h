// Test and benchmark helpers for visibility/: simple flat-faced meshes and their 4x4
// tessellation, built without mesh/'s G1 code. Not for production use.
//
// TessellateFlatForTesting splits every flat geometry triangle linearly into the 16
// sub-triangles of SubTriangleCorners, sharing lattice nodes on shared edges and
// vertices: structurally exactly what the G1 tessellation of a flat-faced mesh is.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "io/rigid3d.h"
#include "mesh/tessellation.h"

namespace facets {

// cam_from_world of a camera at `centre` looking at `target` (COLMAP frame: x right,
// y down, z forward), image up towards world +z, or +y when looking straight up or down.
Rigid3d LookAtForTesting(const Eigen::Vector3d& centre, const Eigen::Vector3d& target);

// A plain triangle mesh: vertices (#V) and faces (#F by 3 vertex indices,
// counter-clockwise seen from the side the normal points to = the outside).
struct FlatMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
};

// Appends an axis-aligned closed box [min, max] with outward normals; the bottom face
// is left out when `with_bottom` is false (a box standing on the ground).
void AppendBoxForTesting(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                         bool with_bottom, FlatMesh* mesh);

// Appends a regular grid of nx by ny quads (2 triangles each) over
// [x0, x1] x [y0, y1] with heights z(x, y), normals pointing up (+z).
template <typename HeightFn>
void AppendGridForTesting(double x0, double y0, double x1, double y1, int nx, int ny,
                          HeightFn z, FlatMesh* mesh) {
  const int base = static_cast<int>(mesh->vertices.size());
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      const double x = x0 + (x1 - x0) * i / nx;
      const double y = y0 + (y1 - y0) * j / ny;
      mesh->vertices.emplace_back(x, y, z(x, y));
    }
  }
  auto id = [&](int i, int j) { return base + j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      mesh->faces.emplace_back(id(i, j), id(i + 1, j), id(i + 1, j + 1));
      mesh->faces.emplace_back(id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  }
}

// The 4x4 linear tessellation of a flat-faced mesh (shared nodes on shared edges).
Tessellation TessellateFlatForTesting(const FlatMesh& mesh);

}  // namespace facets
