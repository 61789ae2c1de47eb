#include "mesh/sector_rings.h"

#include <algorithm>

namespace facets {

std::vector<std::vector<SectorRing>> CreaseSectorRings(const TinMesh& mesh, const CornerNormals& corners) {
  std::vector<std::vector<SectorRing>> result(mesh.n_vertices());
  for (auto v : mesh.vertices()) {
    const int sectors = corners.vertex_sectors[v.idx()];
    if (sectors <= 1) continue;
    std::vector<SectorRing> rings(sectors);
    for (auto h : mesh.vih_range(v)) {  // halfedges into v: their face's corner at v
      if (mesh.is_boundary(h)) continue;
      const int s = corners.corner_sector[h.idx()];
      if (s < 0 || s >= sectors) continue;
      rings[s].normal = corners.normals[h.idx()];
      const int a = mesh.from_vertex_handle(h).idx();
      const int b = mesh.to_vertex_handle(mesh.next_halfedge_handle(h)).idx();
      for (int w : {a, b}) {
        if (std::find(rings[s].ring.begin(), rings[s].ring.end(), w) == rings[s].ring.end()) {
          rings[s].ring.push_back(w);
        }
      }
    }
    for (auto& r : rings) {
      if (r.ring.size() >= 2) result[v.idx()].push_back(std::move(r));
    }
  }
  return result;
}

}  // namespace facets
