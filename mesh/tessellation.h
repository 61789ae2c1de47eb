// Tessellation of the G1 surface into planar sub-triangles, and the grey-value lattice
// on the same split (DESIGN.md section 3).
//
// Each geometry triangle f with vertices (V0, V1, V2) (in OpenMesh's face-vertex
// order) is split regularly into kSubdivisions^2 = 16 sub-triangles in barycentric
// coordinates. The lattice nodes of that split are the tessellation points: they lie
// on the G1 surface, and they are also the grey nodes (one object grey value per node,
// linear inside each sub-triangle = grey facet). Nodes on shared edges and vertices
// are shared between triangles, so there are V + 3E + 3F of them for the 4x4 split.
//
// Sub-triangle s belongs to geometry face s / 16 and has local index k = s % 16; the
// barycentric coordinates of its three corners within the face are fixed per k
// (SubTriangleCorners). A point with Embree barycentrics (u, v) in sub-triangle s has
// face barycentrics  (1-u-v) * C0 + u * C1 + v * C2  with C = SubTriangleCorners(k),
// and grey-facet barycentrics (1-u-v, u, v) on the nodes triangles[s].
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

namespace facets {

constexpr int kSubdivisions = 4;
constexpr int kSubTrianglesPerFace = kSubdivisions * kSubdivisions;

struct Tessellation {
  // Lattice nodes = grey nodes, on the G1 surface, local object coordinates.
  std::vector<Eigen::Vector3d> points;
  // Planar sub-triangles (= grey facets), kSubTrianglesPerFace per geometry face, in
  // face order; corners are indices into points, counter-clockwise seen from the
  // side the face normal points to.
  std::vector<Eigen::Vector3i> triangles;
  // For each point: the geometry face it was generated from and its barycentric
  // coordinates (b0, b1, b2) there (for shared nodes: the first face that made it).
  std::vector<int> point_face;
  std::vector<Eigen::Vector3d> point_barycentric;

  int NumFaces() const { return static_cast<int>(triangles.size()) / kSubTrianglesPerFace; }
};

// Barycentric coordinates (b0, b1, b2) of the three corners of local sub-triangle k
// (0 <= k < 16) within its geometry face; corners ordered counter-clockwise like the
// face.
const std::array<Eigen::Vector3d, 3>& SubTriangleCorners(int k);

// Face barycentrics of a point given by Embree-style (u, v) in sub-triangle k.
inline Eigen::Vector3d FaceBarycentric(int k, double u, double v) {
  const auto& c = SubTriangleCorners(k);
  return (1.0 - u - v) * c[0] + u * c[1] + v * c[2];
}

}  // namespace facets
