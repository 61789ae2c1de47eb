// Quaternary (1-to-4) subdivision that keeps the G1 surface's shape.
#pragma once

#include "mesh/tin.h"

namespace facets {

struct SubdivisionOptions {
  // true (default): new edge vertices take the G1 surface normal there (the edge normal
  // field at s = 1/2) and old vertices keep theirs, so the refined G1 surface
  // reproduces the old one to the interpolant's approximation order.
  // false: all vertex normals are recomputed as the mean of adjacent face normals
  // (UpdateVertexNormals). That moves the surface by O(h^3) (the mean of face
  // normals is only a second-order estimate); the engine does it anyway after each
  // adjustment step.
  bool keep_g1_normals = true;
  void Check() const {}
};

// Returns the subdivided mesh. Layout (so callers can map data between levels):
// old vertex v keeps index v; the new vertex on old edge e has index V + e; old face f
// becomes faces 4f..4f+3 with corners (v0, m01, m20), (m01, v1, m12), (m20, m12, v2),
// (m01, m12, m20), where (v0, v1, v2) is the old face's vertex order and mab is the
// G1 boundary-curve midpoint of edge ab. There is no re-triangulation.
TinMesh QuaternarySubdivide(const TinMesh& mesh, const SubdivisionOptions& options = {});
// Same on the surface with creases (mesh/creases.h): new vertices on crease edges at the
// chord midpoint, elsewhere on the curves of the sectors' corner normals, so a ridge
// stays sharp from level to level.
struct CornerNormals;
TinMesh QuaternarySubdivide(const TinMesh& mesh, const CornerNormals& corners,
                            const SubdivisionOptions& options = {});

// Barycentrics within the parent face of corner c of child face 4f + child.
Eigen::Vector3d ChildCornerInParent(int child, int c);

}  // namespace facets
