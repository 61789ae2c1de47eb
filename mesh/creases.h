// Crease edges and corner normals: where the G1 surface must not round a sharp edge.
//
// Built-up areas are full of creases (roof ridges, eaves, wall-roof and wall-ground
// edges). A G1 surface through vertex normals averaged across such an edge rounds it
// over a whole triangle on each side (a 20-degree gable roof on 2 m triangles bulges
// by about 0.1 m), and the adjustment then pulls the crease vertices away from the
// true edge to compensate. So: an interior edge whose two face normals differ by more
// than a crease angle is a crease edge; around a vertex on creases, the faces fall
// into sectors separated by crease edges, and each face's patch uses its sector's
// normal at that corner (the angle-weighted mean of the sector's face normals, made
// orthogonal to the bounding crease edges). The boundary curve of a crease edge is the
// straight chord for both faces (G1Patch with straight edges): the surface stays
// continuous (G0) across creases, G1 across every other edge, and planar roof faces
// are reproduced exactly.
//
// The vertex normals (displacement directions of the adjustment) are not changed.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "mesh/g1_patch.h"
#include "mesh/tin.h"

namespace facets {

struct CornerNormals {
  // Normal at the to-vertex of each halfedge for the face of that halfedge, indexed by
  // halfedge index (entries of boundary halfedges are unused).
  std::vector<Eigen::Vector3d> normals;
  // Sector of that corner at its vertex: 0 .. vertex_sectors[v]-1 (0 off creases).
  std::vector<int> corner_sector;
  std::vector<int> vertex_sectors;  // by vertex index, >= 1
  std::vector<bool> crease_edge;    // by edge index
  int num_crease_edges = 0;
  int num_crease_vertices = 0;
};

// Unit normal of a face (from its corners in order), zero for a face with no area.
Eigen::Vector3d UnitFaceNormal(const TinMesh& mesh, TinMesh::FaceHandle fh);

// Interior edges whose adjacent unit face normals enclose more than crease_angle_deg
// (>= 180: none), and with rounded_ridges the ridge row of a crease rounded over a band of edge rows: an
// edge bent by at least half the angle, whose opposite corners' vertex normals enclose
// more than the angle, and that bends most among the roughly parallel edges at those
// corners (curvature regularisation keeps a ridge round until it is declared a crease).
std::vector<bool> DetectCreaseEdges(const TinMesh& mesh, double crease_angle_deg, bool rounded_ridges = false);

// Corner normals for a given set of crease edges (kept fixed while a window is
// adjusted, so that the grey lattice keeps its node indices). Vertex normals must be
// up to date (UpdateVertexNormals).
CornerNormals ComputeCornerNormals(const TinMesh& mesh, const std::vector<bool>& crease_edge);
inline CornerNormals ComputeCornerNormals(const TinMesh& mesh, double crease_angle_deg, bool rounded_ridges = false) {
  return ComputeCornerNormals(mesh, DetectCreaseEdges(mesh, crease_angle_deg, rounded_ridges));
}

// Patches with corner normals (compare FacePatch / BuildPatches of mesh/tin.h, which
// use the vertex normals).
G1Patch FacePatch(const TinMesh& mesh, TinMesh::FaceHandle fh, const CornerNormals& corners);
std::vector<G1Patch> BuildPatches(const TinMesh& mesh, const CornerNormals& corners);

}  // namespace facets
