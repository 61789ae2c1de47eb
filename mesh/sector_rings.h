// The 1-ring of a crease vertex split into its sectors (issue 7): the faces between two
// crease edges around the vertex, with the sector's corner normal and the ring
// vertices of those faces. Lets the curvature regularisation ask "flat within each
// sector" at a crease vertex (an eave: flat roof side, flat wall side) instead of
// leaving the vertex unregularised, which lets crumpled walls stay crumpled.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "mesh/creases.h"
#include "mesh/tin.h"

namespace facets {

struct SectorRing {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // the sector's corner normal
  std::vector<int> ring;                              // ring vertices of its faces
};

// Per vertex: empty when the vertex has one sector (off creases), else one entry per
// sector with at least two ring vertices.
std::vector<std::vector<SectorRing>> CreaseSectorRings(const TinMesh& mesh, const CornerNormals& corners);

}  // namespace facets
