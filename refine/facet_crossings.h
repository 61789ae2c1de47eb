// Crossing surface facets in the products: the output may not intersect itself.
//
// The TIN can be free of self-intersections while the G1 tessellation over it is not: a
// Nielson patch bulges off its chord by up to a few percent of an edge, and where two
// sheets of the surface come close (a wall under its eave, the two sides of a thin
// fold, a pocket) bulging patches cross although their chords do not. FlattenCrossingFacets
// pulls the patches of the TIN faces whose facets cross toward their chords until no
// facets cross: every tessellation node becomes chord + w * (node - chord), w the
// barycentric blend of per-TIN-vertex weights that start at 1 and go 0.5, 0.25, 0 at the
// vertices of crossing faces, round by round. A node on an edge depends only on the
// edge's two vertices, so the surface stays watertight; with every weight 0 it is the
// TIN itself (split into 16 flat facets a face), so only crossings of the TIN remain.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "mesh/tessellation.h"
#include "mesh/tin.h"

namespace facets {

struct FacetCrossingRepair {
  int pairs_found = -1;      // crossing facet pairs of the tessellation as given (-1: not checked)
  int pairs_left = 0;        // after the last round: crossings of the TIN's own chords
  int rounds = 0;            // rounds that changed weights
  int vertices_weighted = 0; // TIN vertices whose weight went below 1
  int faces_changed = 0;     // TIN faces with such a vertex (their nodes moved)
  int unchecked_facets = 0;  // facets left out of the check (non-manifold after merging duplicates)
  double max_move = 0.0;     // largest node move (m)
  std::string Brief() const;
};

// `mesh` is the TIN `tess` was made from (same faces, vertex positions the patches
// interpolate). Nodes that coincide (crease duplicates) are one vertex for the check.
FacetCrossingRepair FlattenCrossingFacets(const TinMesh& mesh, Tessellation* tess, int max_rounds = 6);

// Crossing facet pairs of a tessellation (CGAL self_intersections on the facets with
// coinciding nodes merged), for tests and reports.
int CountCrossingFacets(const Tessellation& tess);

// The same for any triangle mesh (an evaluated surface.ply, another tool's mesh):
// crossing pairs, and the triangles left out of the check (degenerate once coinciding
// points are merged, or non-manifold).
struct TriangleCrossings {
  int pairs = 0;
  int unchecked = 0;
};
TriangleCrossings CountCrossingTriangles(const std::vector<Eigen::Vector3d>& points,
                                         const std::vector<Eigen::Vector3i>& triangles);

}  // namespace facets
