#include "mesh/creases.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numeric>

namespace facets {
namespace {

Eigen::Vector3d UnitFaceNormal(const TinMesh& mesh, TinMesh::FaceHandle fh) {
  auto it = mesh.cfv_iter(fh);
  const Eigen::Vector3d p0 = ToEigen(mesh.point(*it));
  const Eigen::Vector3d p1 = ToEigen(mesh.point(*++it));
  const Eigen::Vector3d p2 = ToEigen(mesh.point(*++it));
  const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
  const double len = n.norm();
  return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

std::vector<bool> DetectCreaseEdges(const TinMesh& mesh, double crease_angle_deg) {
  std::vector<bool> crease(mesh.n_edges(), false);
  if (crease_angle_deg >= 180.0) return crease;
  std::vector<Eigen::Vector3d> face_normal(mesh.n_faces());
  for (auto fh : mesh.faces()) face_normal[fh.idx()] = UnitFaceNormal(mesh, fh);
  const double cos_crease = std::cos(crease_angle_deg * M_PI / 180.0);
  for (auto eh : mesh.edges()) {
    if (mesh.is_boundary(eh)) continue;
    const auto f0 = mesh.face_handle(mesh.halfedge_handle(eh, 0));
    const auto f1 = mesh.face_handle(mesh.halfedge_handle(eh, 1));
    crease[eh.idx()] = face_normal[f0.idx()].dot(face_normal[f1.idx()]) < cos_crease;
  }
  return crease;
}

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
    const Eigen::Vector3d p = ToEigen(mesh.point(vh));
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
    // Sectors: faces joined across non-crease edges at the vertex (union-find).
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
            if (ei == ej && !out.crease_edge[ei]) parent[Find(parent, i)] = Find(parent, j);
          }
        }
      }
    }
    int sector = 0;
    for (int root = 0; root < m; ++root) {
      if (Find(parent, root) != root) continue;
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      std::vector<Eigen::Vector3d> crease_dirs;
      for (int i = 0; i < m; ++i) {
        if (Find(parent, i) != root) continue;
        const auto heh = corner[i];
        const auto fh = mesh.face_handle(heh);
        const Eigen::Vector3d e1 = ToEigen(mesh.point(mesh.from_vertex_handle(heh))) - p;
        const Eigen::Vector3d e2 =
            ToEigen(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(heh)))) - p;
        sum += std::atan2(e1.cross(e2).norm(), e1.dot(e2)) * face_normal[fh.idx()];
        const std::array<int, 2> edges = edges_of(i);
        const Eigen::Vector3d dirs[2] = {e1, e2};
        for (int k = 0; k < 2; ++k) {
          if (out.crease_edge[edges[k]]) crease_dirs.push_back(dirs[k].normalized());
        }
      }
      Eigen::Vector3d n = sum.normalized();
      // Make the crease chords lie in the tangent plane: the face plane spanned by two
      // non-parallel creases, or the normal with one crease direction projected out.
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
      for (int i = 0; i < m; ++i) {
        if (Find(parent, i) != root) continue;
        out.normals[corner[i].idx()] = n;
        out.corner_sector[corner[i].idx()] = sector;
      }
      ++sector;
    }
    out.vertex_sectors[vh.idx()] = std::max(sector, 1);
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
