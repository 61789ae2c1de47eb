#include "mesh/tessellation.h"

#include "mesh/creases.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace facets {

const std::array<Eigen::Vector3d, 3>& SubTriangleCorners(int k) {
  // Built once: lattice node (i, j) with i + j <= n has barycentrics
  // ((n-i-j)/n, i/n, j/n). Upward triangles then downward ones, row by row.
  static const std::array<std::array<Eigen::Vector3d, 3>, kSubTrianglesPerFace> corners = [] {
    std::array<std::array<Eigen::Vector3d, 3>, kSubTrianglesPerFace> out;
    const double n = kSubdivisions;
    auto node = [n](int i, int j) { return Eigen::Vector3d((n - i - j) / n, i / n, j / n); };
    int k = 0;
    for (int j = 0; j < kSubdivisions; ++j) {
      for (int i = 0; i + j < kSubdivisions; ++i) {
        out[k++] = {node(i, j), node(i + 1, j), node(i, j + 1)};
        if (i + j + 1 < kSubdivisions) {
          out[k++] = {node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)};
        }
      }
    }
    return out;
  }();
  if (k < 0 || k >= kSubTrianglesPerFace) throw std::out_of_range("SubTriangleCorners");
  return corners[k];
}

}  // namespace facets

namespace facets {
namespace {

constexpr int kN = kSubdivisions;

// Index of sub-triangle (i, j, downward) in SubTriangleCorners' order.
int SubTriangleIndex(int i, int j, bool down) {
  int k = 0;
  for (int r = 0; r < j; ++r) k += 2 * (kN - r) - 1;
  return k + 2 * i + (down ? 1 : 0);
}

// Interior lattice node (i, j) -> 0..(n-1)(n-2)/2-1, row by row.
int InteriorIndex(int i, int j) {
  int k = 0;
  for (int r = 1; r < j; ++r) k += kN - 1 - r;
  return k + (i - 1);
}

}  // namespace

SubTriangleLocation LocateSubTriangle(const Eigen::Vector3d& b) {
  const double x = kN * b[1], y = kN * b[2];
  int i = std::clamp(static_cast<int>(std::floor(x)), 0, kN - 1);
  int j = std::clamp(static_cast<int>(std::floor(y)), 0, kN - 1);
  while (i + j > kN - 1) {
    if (x - i >= y - j) {
      --i;
    } else {
      --j;
    }
  }
  const double fx = x - i, fy = y - j;
  SubTriangleLocation loc;
  if (fx + fy <= 1.0 || i + j == kN - 1) {
    loc.k = SubTriangleIndex(i, j, false);
    loc.u = fx;
    loc.v = fy;
  } else {
    loc.k = SubTriangleIndex(i, j, true);
    loc.v = 1.0 - fx;
    loc.u = fx + fy - 1.0;
  }
  return loc;
}

namespace {

constexpr int kEdgeNodes = kN - 1;                    // lattice nodes inside an edge
constexpr int kInner = (kN - 1) * (kN - 2) / 2;       // lattice nodes inside a face

// Where the lattice nodes of a mesh go in Tessellation::points: vertices, then edge
// nodes, then face-interior nodes, then the duplicates along creases (a crease edge's
// nodes again for its second face, a vertex's node again for each further sector).
struct NodeLayout {
  int nv = 0, ne = 0;
  bool split = false;                // with crease tables
  std::vector<int> crease_edge_base;  // by edge: first duplicate node, -1 off creases
  std::vector<int> sector_base;       // by vertex: node of its sector 1, -1 with one sector
  size_t num_points = 0;
};

NodeLayout LayOutNodes(const TinMesh& mesh, const CornerNormals& creases) {
  NodeLayout layout;
  layout.nv = static_cast<int>(mesh.n_vertices());
  layout.ne = static_cast<int>(mesh.n_edges());
  const int nf = static_cast<int>(mesh.n_faces());
  layout.num_points = static_cast<size_t>(layout.nv) + static_cast<size_t>(kEdgeNodes) * layout.ne +
                      static_cast<size_t>(kInner) * nf;
  // Duplicated nodes along creases (empty tables without creases).
  layout.split = !creases.crease_edge.empty();
  if (!layout.split) return layout;
  layout.crease_edge_base.assign(layout.ne, -1);
  for (int e = 0; e < layout.ne; ++e) {
    if (!creases.crease_edge[e]) continue;
    layout.crease_edge_base[e] = static_cast<int>(layout.num_points);
    layout.num_points += kEdgeNodes;
  }
  layout.sector_base.assign(layout.nv, -1);
  for (int v = 0; v < layout.nv; ++v) {
    if (creases.vertex_sectors[v] <= 1) continue;
    layout.sector_base[v] = static_cast<int>(layout.num_points);
    layout.num_points += creases.vertex_sectors[v] - 1;
  }
  return layout;
}

// Topology of face f: its lattice node (i, j) -> global node index, the first face of
// each node recorded with the node's barycentrics, and the face's sub-triangles.
void AddFaceLattice(const TinMesh& mesh, const CornerNormals& creases, const NodeLayout& layout, int f,
                    Tessellation* tess) {
  const int nv = layout.nv, ne = layout.ne;
  const bool split = layout.split;
  std::array<int, (kN + 1) * (kN + 1)> node;
  const auto fh = mesh.face_handle(f);
  std::array<TinMesh::HalfedgeHandle, 3> h;
  std::array<int, 3> v;
  int c = 0;
  for (auto he : mesh.fh_range(fh)) h[c++] = he;
  for (c = 0; c < 3; ++c) v[c] = mesh.to_vertex_handle(h[c]).idx();
  // Edge from v_a to v_b is the edge of h_{a+1}; node at position t (1..n-1) from v_a.
  auto edge_node = [&](int a, int b, int t) {
    const auto heh = h[(a + 1) % 3];
    const int e = mesh.edge_handle(heh).idx();
    const int local = v[a] < v[b] ? t - 1 : kN - t - 1;
    if (split && layout.crease_edge_base[e] >= 0 && mesh.halfedge_handle(mesh.edge_handle(heh), 1) == heh) {
      return layout.crease_edge_base[e] + local;
    }
    return nv + kEdgeNodes * e + local;
  };
  // Vertex node of corner c: the vertex itself, or its sector's duplicate.
  auto vertex_node = [&](int c) {
    if (!split) return v[c];
    const int sector = creases.corner_sector[h[c].idx()];
    return sector == 0 ? v[c] : layout.sector_base[v[c]] + sector - 1;
  };
  for (int j = 0; j <= kN; ++j) {
    for (int i = 0; i + j <= kN; ++i) {
      int g;
      if (i == 0 && j == 0) {
        g = vertex_node(0);
      } else if (i == kN) {
        g = vertex_node(1);
      } else if (j == kN) {
        g = vertex_node(2);
      } else if (j == 0) {
        g = edge_node(0, 1, i);
      } else if (i + j == kN) {
        g = edge_node(1, 2, j);
      } else if (i == 0) {
        g = edge_node(2, 0, kN - j);
      } else {
        g = nv + kEdgeNodes * ne + kInner * f + InteriorIndex(i, j);
      }
      node[j * (kN + 1) + i] = g;
      if (tess->point_face[g] < 0) {
        tess->point_face[g] = f;
        tess->point_barycentric[g] = Eigen::Vector3d(kN - i - j, i, j) / static_cast<double>(kN);
      }
    }
  }
  for (int k = 0; k < kSubTrianglesPerFace; ++k) {
    const auto& corners = SubTriangleCorners(k);
    Eigen::Vector3i t;
    for (int c2 = 0; c2 < 3; ++c2) {
      const int i = static_cast<int>(std::lround(corners[c2][1] * kN));
      const int j = static_cast<int>(std::lround(corners[c2][2] * kN));
      t[c2] = node[j * (kN + 1) + i];
    }
    tess->triangles[static_cast<size_t>(kSubTrianglesPerFace) * f + k] = t;
  }
}

}  // namespace

Tessellation Tessellate(const TinMesh& mesh) { return Tessellate(mesh, BuildPatches(mesh)); }

Tessellation Tessellate(const TinMesh& mesh, const std::vector<G1Patch>& patches) {
  CornerNormals none;
  return Tessellate(mesh, patches, none);
}

Tessellation Tessellate(const TinMesh& mesh, const std::vector<G1Patch>& patches,
                        const CornerNormals& creases) {
  if (patches.size() != mesh.n_faces()) {
    throw std::invalid_argument("Tessellate: patch count does not match the face count");
  }
  if (mesh.has_vertex_status() && mesh.has_face_status()) {
    for (auto f : mesh.all_faces()) {
      if (mesh.status(f).deleted()) {
        throw std::invalid_argument("Tessellate: mesh has deleted faces (garbage_collection)");
      }
    }
  }
  const int nf = static_cast<int>(mesh.n_faces());
  const NodeLayout layout = LayOutNodes(mesh, creases);
  const size_t num_points = layout.num_points;
  Tessellation tess;
  tess.points.resize(num_points);
  tess.point_face.assign(num_points, -1);
  tess.point_barycentric.assign(num_points, Eigen::Vector3d::Zero());
  tess.triangles.resize(static_cast<size_t>(kSubTrianglesPerFace) * nf);
  // Topology (serial, cheap).
  for (int f = 0; f < nf; ++f) AddFaceLattice(mesh, creases, layout, f, &tess);
  for (size_t p = 0; p < num_points; ++p) {
    if (tess.point_face[p] < 0) {
      throw std::invalid_argument("Tessellate: isolated vertex " + std::to_string(p) +
                                  " (no adjacent face)");
    }
  }
  UpdateTessellationPoints(patches, &tess);
  return tess;
}

void UpdateTessellationPoints(const std::vector<G1Patch>& patches, Tessellation* tess) {
  if (static_cast<int>(patches.size()) != tess->NumFaces()) {
    throw std::invalid_argument("UpdateTessellationPoints: face count changed");
  }
  const size_t n = tess->points.size();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t p = r.begin(); p != r.end(); ++p) {
                        const Eigen::Vector3d& b = tess->point_barycentric[p];
                        tess->points[p] = patches[tess->point_face[p]].Evaluate(b[1], b[2]);
                      }
                    });
}

void UpdateTessellationPoints(const TinMesh& mesh, Tessellation* tess) {
  UpdateTessellationPoints(BuildPatches(mesh), tess);
}

}  // namespace facets
