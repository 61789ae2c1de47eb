// Which TIN vertices the images can see at all. A roof that rises over a
// 2.5D start can fold a sheet of the surface under itself: those vertices lie inside
// the building, hidden from every image, and the adjustment has nothing to move them
// with. They are found by casting from every projection centre to every vertex.
#pragma once

#include <vector>

#include "io/image_block.h"
#include "mesh/tin.h"

namespace facets {

// Per vertex: the images whose frame it projects into, towards which its normal faces,
// and whose ray to it meets no other part of the TIN more than `tolerance` (m) before
// the vertex (Embree on the chord triangles). Vertex normals must be set.
std::vector<int> VisibleViews(const TinMesh& mesh, const ImageBlock& block, double tolerance);

}  // namespace facets
