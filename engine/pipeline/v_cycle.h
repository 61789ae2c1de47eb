// V-cycles: the pyramid descended once more from a coarser level whose TIN is put onto
// the finished finest surface. Each level transition loses walls at eaves and feet even
// from a perfect coarser TIN, and a coarse level run from the tie-point start commits
// some walls metres off; going
// back up with the finest surface's shape gives the coarse level a start that is right
// where the finest level got it right, and the descent another chance where it did not.
#pragma once

#include "mesh/tessellation.h"
#include "mesh/tin.h"

namespace facets {

struct ProjectionReport {
  int moved = 0;    // vertices moved onto the surface
  int missed = 0;   // vertices whose normal line meets the surface nowhere within reach
  int limited = 0;  // moves the fold guard halved or undid
  double median_move = 0.0;  // of the moved vertices (m)
  double max_move = 0.0;
};

// Moves every vertex of `mesh` along its normal onto `surface` (the nearer hit in either
// direction within max_distance); vertices without a hit stay. Steps that would fold the
// surface are halved or undone (mesh/surface_validity.h). Vertex normals are updated.
ProjectionReport ProjectAlongNormals(TinMesh* mesh, const Tessellation& surface, double max_distance);

}  // namespace facets
