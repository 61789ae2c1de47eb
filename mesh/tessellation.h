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

#include "mesh/g1_patch.h"
#include "mesh/tin.h"

namespace facets {

struct CornerNormals;

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

// Inverse of FaceBarycentric: the sub-triangle k containing face barycentrics b (points
// on shared sub-triangle edges go to one of them) and the Embree-style (u, v) there.
struct SubTriangleLocation {
  int k = 0;
  double u = 0.0, v = 0.0;
};
SubTriangleLocation LocateSubTriangle(const Eigen::Vector3d& b);

// Node index layout (stable for one mesh topology): vertex v -> v; the 3 nodes inside
// edge e -> V + 3e + t, t = 0..2 counted from the edge's lower-index vertex; the 3
// nodes inside face f -> V + 3E + 3f + t. The face vertex order is OpenMesh's
// fv_range order (also the order of FacePatch), so triangles are counter-clockwise
// seen from the side the face normal points to.
// Points are evaluated on the G1 surface (TBB-parallel). The mesh must have no deleted
// elements (call garbage_collection() after removals).
Tessellation Tessellate(const TinMesh& mesh);
// Same, with patches already built (BuildPatches(mesh)).
Tessellation Tessellate(const TinMesh& mesh, const std::vector<G1Patch>& patches);
// With crease edges (mesh/creases.h): the grey nodes on crease edges and crease
// vertices are duplicated per side and sector, so object grey values may jump across a
// crease (the two planes of a gable roof are lit differently). Layout: as above, then
// 3 nodes for every crease edge (used by the face of the edge's halfedge 1), then one
// node for every further sector of each crease vertex. Duplicates coincide in space,
// so the tessellated surface stays watertight.
Tessellation Tessellate(const TinMesh& mesh, const std::vector<G1Patch>& patches,
                        const CornerNormals& creases);

// After vertices (and normals) moved but the topology did not change: recomputes only
// tess->points (node indices, triangles and the node-to-face map stay). Throws
// std::invalid_argument when the mesh's face count does not match.
void UpdateTessellationPoints(const TinMesh& mesh, Tessellation* tess);
void UpdateTessellationPoints(const std::vector<G1Patch>& patches, Tessellation* tess);

}  // namespace facets
