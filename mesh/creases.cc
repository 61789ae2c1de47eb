#include "mesh/creases.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace facets {
namespace {

Eigen::Vector3d AreaFaceNormal(const TinMesh& mesh, TinMesh::FaceHandle fh) {
  auto it = mesh.cfv_iter(fh);
  const Eigen::Vector3d p0 = ToEigen(mesh.point(*it));
  const Eigen::Vector3d p1 = ToEigen(mesh.point(*++it));
  const Eigen::Vector3d p2 = ToEigen(mesh.point(*++it));
  return (p1 - p0).cross(p2 - p0);
}

int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

Eigen::Vector3d UnitFaceNormal(const TinMesh& mesh, TinMesh::FaceHandle fh) {
  const Eigen::Vector3d n = AreaFaceNormal(mesh, fh);
  const double len = n.norm();
  return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

std::vector<bool> DetectCreaseEdges(const TinMesh& mesh, double crease_angle_deg, bool rounded_ridges) {
  std::vector<bool> crease(mesh.n_edges(), false);
  if (crease_angle_deg >= 180.0) return crease;
  std::vector<Eigen::Vector3d> face_normal(mesh.n_faces());
  for (auto fh : mesh.faces()) face_normal[fh.idx()] = UnitFaceNormal(mesh, fh);
  const double cos_crease = std::cos(crease_angle_deg * M_PI / 180.0);
  const double cos_half = std::cos(0.5 * crease_angle_deg * M_PI / 180.0);
  std::vector<double> cos_dihedral(mesh.n_edges(), 1.0);
  for (auto eh : mesh.edges()) {
    if (mesh.is_boundary(eh)) continue;
    const auto f0 = mesh.face_handle(mesh.halfedge_handle(eh, 0));
    const auto f1 = mesh.face_handle(mesh.halfedge_handle(eh, 1));
    cos_dihedral[eh.idx()] = face_normal[f0.idx()].dot(face_normal[f1.idx()]);
    crease[eh.idx()] = cos_dihedral[eh.idx()] < cos_crease;
  }
  if (!rounded_ridges) return crease;
  // Area-weighted vertex normals of the current geometry (the mesh's stored normals
  // may be a step behind).
  std::vector<Eigen::Vector3d> vertex_normal(mesh.n_vertices(), Eigen::Vector3d::Zero());
  for (auto fh : mesh.faces()) {
    const Eigen::Vector3d area_normal = AreaFaceNormal(mesh, fh);
    for (auto vh : mesh.fv_range(fh)) vertex_normal[vh.idx()] += area_normal;
  }
  for (auto& n : vertex_normal) {
    const double len = n.norm();
    if (len > 0.0) n /= len;
  }
  // A ridge the regularisation has rounded over two or three rows of edges: no single
  // edge reaches the crease angle, but the bend across the edge's band does. The band
  // is measured between the vertex normals of the two opposite corners (each averages
  // the faces one row further out), and only the most bent edge of the rows, a local
  // maximum against the roughly parallel edges at those corners, becomes the crease.
  // It must bend by half the crease angle itself, so smooth curvature (the seed's
  // cylinders, 3.4 degrees per 2 m) and noise stay G1.
  const double cos_parallel = std::cos(30.0 * M_PI / 180.0);
  std::vector<bool> on_crease(mesh.n_vertices(), false);
  for (auto eh : mesh.edges()) {
    if (!crease[eh.idx()]) continue;
    on_crease[mesh.to_vertex_handle(mesh.halfedge_handle(eh, 0)).idx()] = true;
    on_crease[mesh.from_vertex_handle(mesh.halfedge_handle(eh, 0)).idx()] = true;
  }
  for (auto eh : mesh.edges()) {
    if (crease[eh.idx()] || mesh.is_boundary(eh) || cos_dihedral[eh.idx()] >= cos_half) continue;
    const auto h0 = mesh.halfedge_handle(eh, 0);
    const auto h1 = mesh.halfedge_handle(eh, 1);
    const auto c = mesh.to_vertex_handle(mesh.next_halfedge_handle(h0));
    const auto d = mesh.to_vertex_handle(mesh.next_halfedge_handle(h1));
    // A corner on the border has half a ring: its normal says nothing about the band;
    // a corner on a crease already explains the bend (an edge from a sharp ridge
    // down into the roof plane).
    if (mesh.is_boundary(c) || mesh.is_boundary(d) || on_crease[c.idx()] || on_crease[d.idx()]) continue;
    if (vertex_normal[c.idx()].dot(vertex_normal[d.idx()]) >= cos_crease) continue;
    const Eigen::Vector3d dir =
        (ToEigen(mesh.point(mesh.to_vertex_handle(h0))) - ToEigen(mesh.point(mesh.from_vertex_handle(h0)))).normalized();
    bool maximum = true;
    for (auto corner : {c, d}) {
      for (auto heh : mesh.voh_range(corner)) {
        const auto other = mesh.edge_handle(heh);
        if (other == eh || mesh.is_boundary(other)) continue;
        const Eigen::Vector3d odir =
            (ToEigen(mesh.point(mesh.to_vertex_handle(heh))) - ToEigen(mesh.point(corner))).normalized();
        if (std::abs(odir.dot(dir)) < cos_parallel) continue;
        if (cos_dihedral[other.idx()] < cos_dihedral[eh.idx()]) maximum = false;
      }
    }
    crease[eh.idx()] = maximum;
  }
  return crease;
}

namespace {

// The normal of a sector at its vertex: the angle-weighted mean of its faces' normals
// (face_normal, by face index), made orthogonal to the crease edges that bound it so
// that the crease chords lie in the tangent plane: the face plane spanned by two
// non-parallel creases, or the normal with one crease direction projected out.
// corner: the faces around the vertex by their incoming halfedges; in_sector: which
// of them belong to the sector; edges_of(i): the two edges at the vertex of corner i.
template <typename EdgesOf>
Eigen::Vector3d SectorNormal(const TinMesh& mesh, const Eigen::Vector3d& p,
                             const std::vector<TinMesh::HalfedgeHandle>& corner, const std::vector<bool>& in_sector,
                             const std::vector<Eigen::Vector3d>& face_normal, const std::vector<bool>& crease_edge,
                             const EdgesOf& edges_of) {
  const int m = static_cast<int>(corner.size());
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> crease_dirs;
  for (int i = 0; i < m; ++i) {
    if (!in_sector[i]) continue;
    const auto heh = corner[i];
    const auto fh = mesh.face_handle(heh);
    const Eigen::Vector3d e1 = ToEigen(mesh.point(mesh.from_vertex_handle(heh))) - p;
    const Eigen::Vector3d e2 = ToEigen(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(heh)))) - p;
    sum += std::atan2(e1.cross(e2).norm(), e1.dot(e2)) * face_normal[fh.idx()];
    const std::array<int, 2> edges = edges_of(i);
    const Eigen::Vector3d dirs[2] = {e1, e2};
    for (int k = 0; k < 2; ++k) {
      if (crease_edge[edges[k]]) crease_dirs.push_back(dirs[k].normalized());
    }
  }
  Eigen::Vector3d n = sum.normalized();
  Eigen::Vector3d first = Eigen::Vector3d::Zero(), second = Eigen::Vector3d::Zero();
  for (const auto& d : crease_dirs) {
    if (first.isZero()) {
      first = d;
    } else if (first.cross(d).norm() > 0.2 && second.isZero()) {
      second = d;
    }
  }
  if (!second.isZero()) {
    Eigen::Vector3d c = first.cross(second).normalized();
    n = c.dot(n) < 0.0 ? Eigen::Vector3d(-c) : c;
  } else if (!first.isZero()) {
    const Eigen::Vector3d projected = n - n.dot(first) * first;
    if (projected.norm() > 1e-6) n = projected.normalized();
  }
  return n;
}

// Sectors of a vertex on creases: its faces (corner, by incoming halfedge) joined
// across non-crease edges at the vertex (union-find); each corner gets its sector's
// normal and index. Returns the number of sectors.
int SplitIntoSectors(const TinMesh& mesh, TinMesh::VertexHandle vh, const std::vector<TinMesh::HalfedgeHandle>& corner,
                     const std::vector<Eigen::Vector3d>& face_normal, CornerNormals* out) {
  const Eigen::Vector3d p = ToEigen(mesh.point(vh));
  const int m = static_cast<int>(corner.size());
  std::vector<int> parent(m);
  std::iota(parent.begin(), parent.end(), 0);
  auto edges_of = [&](int i) {
    // The incoming halfedge's edge and the outgoing one's (next of the corner).
    return std::array<int, 2>{mesh.edge_handle(corner[i]).idx(),
                              mesh.edge_handle(mesh.next_halfedge_handle(corner[i])).idx()};
  };
  for (int i = 0; i < m; ++i) {
    for (int j = i + 1; j < m; ++j) {
      for (int ei : edges_of(i)) {
        for (int ej : edges_of(j)) {
          if (ei == ej && !out->crease_edge[ei]) parent[Find(parent, i)] = Find(parent, j);
        }
      }
    }
  }
  int sector = 0;
  for (int root = 0; root < m; ++root) {
    if (Find(parent, root) != root) continue;
    std::vector<bool> in_sector(m);
    for (int i = 0; i < m; ++i) in_sector[i] = Find(parent, i) == root;
    const Eigen::Vector3d n = SectorNormal(mesh, p, corner, in_sector, face_normal, out->crease_edge, edges_of);
    for (int i = 0; i < m; ++i) {
      if (!in_sector[i]) continue;
      out->normals[corner[i].idx()] = n;
      out->corner_sector[corner[i].idx()] = sector;
    }
    ++sector;
  }
  return sector;
}

}  // namespace

CornerNormals ComputeCornerNormals(const TinMesh& mesh, const std::vector<bool>& crease_edge) {
  CornerNormals out;
  out.normals.assign(mesh.n_halfedges(), Eigen::Vector3d::Zero());
  out.corner_sector.assign(mesh.n_halfedges(), 0);
  out.vertex_sectors.assign(mesh.n_vertices(), 1);
  out.crease_edge = crease_edge;
  out.crease_edge.resize(mesh.n_edges(), false);
  for (bool c : out.crease_edge) out.num_crease_edges += c ? 1 : 0;
  std::vector<Eigen::Vector3d> face_normal(mesh.n_faces());
  for (auto fh : mesh.faces()) face_normal[fh.idx()] = UnitFaceNormal(mesh, fh);

  for (auto vh : mesh.vertices()) {
    const Eigen::Vector3d vertex_normal = ToEigen(mesh.normal(vh));
    // Faces around the vertex, each with its incoming halfedge (the corner) and the
    // two edges at the vertex it touches.
    std::vector<TinMesh::HalfedgeHandle> corner;
    bool on_crease = false;
    for (auto heh : mesh.voh_range(vh)) {
      if (out.crease_edge[mesh.edge_handle(heh).idx()]) on_crease = true;
      if (mesh.face_handle(heh).is_valid()) corner.push_back(mesh.prev_halfedge_handle(heh));
    }
    if (!on_crease) {
      for (auto heh : corner) out.normals[heh.idx()] = vertex_normal;
      continue;
    }
    ++out.num_crease_vertices;
    const int sectors = SplitIntoSectors(mesh, vh, corner, face_normal, &out);
    out.vertex_sectors[vh.idx()] = std::max(sectors, 1);
  }
  return out;
}

G1Patch FacePatch(const TinMesh& mesh, TinMesh::FaceHandle fh, const CornerNormals& corners) {
  // Same vertex order as FacePatch(mesh, fh): the to-vertices of the face's halfedges.
  // Edge i (opposite vertex i) runs from vertex i+1 to vertex i+2: halfedge h[i+2].
  Eigen::Vector3d x[3], n[3];
  std::array<TinMesh::HalfedgeHandle, 3> h;
  int k = 0;
  for (auto heh : mesh.fh_range(fh)) {
    h[k] = heh;
    x[k] = ToEigen(mesh.point(mesh.to_vertex_handle(heh)));
    n[k] = corners.normals[heh.idx()];
    ++k;
  }
  std::array<bool, 3> straight;
  for (int i = 0; i < 3; ++i) straight[i] = corners.crease_edge[mesh.edge_handle(h[(i + 2) % 3]).idx()];
  return G1Patch(x[0], x[1], x[2], n[0], n[1], n[2], straight);
}

std::vector<G1Patch> BuildPatches(const TinMesh& mesh, const CornerNormals& corners) {
  std::vector<G1Patch> patches(mesh.n_faces());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.n_faces(), 1024),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t f = r.begin(); f != r.end(); ++f) {
                        patches[f] = FacePatch(mesh, mesh.face_handle(static_cast<int>(f)), corners);
                      }
                    });
  return patches;
}

}  // namespace facets
