#include "mesh/subdivision.h"

#include "mesh/creases.h"

#include <array>
#include <stdexcept>

namespace facets {

Eigen::Vector3d ChildCornerInParent(int child, int c) {
  static const Eigen::Vector3d v0(1, 0, 0), v1(0, 1, 0), v2(0, 0, 1);
  static const Eigen::Vector3d m01(0.5, 0.5, 0), m12(0, 0.5, 0.5), m20(0.5, 0, 0.5);
  static const std::array<std::array<Eigen::Vector3d, 3>, 4> table = {{
      {v0, m01, m20}, {m01, v1, m12}, {m20, m12, v2}, {m01, m12, m20}}};
  if (child < 0 || child > 3 || c < 0 || c > 2) throw std::out_of_range("ChildCornerInParent");
  return table[child][c];
}

namespace {

// The new vertex on an edge and its normal.
struct EdgeMidpoint {
  Eigen::Vector3d point;
  Eigen::Vector3d normal;
};

template <typename MidpointFn>
TinMesh Subdivide(const TinMesh& mesh, const SubdivisionOptions& options, MidpointFn midpoint) {
  options.Check();
  TinMesh out;
  out.reserve(mesh.n_vertices() + mesh.n_edges(), 2 * mesh.n_edges() + 3 * mesh.n_faces(),
              4 * mesh.n_faces());
  std::vector<TinMesh::VertexHandle> vh;
  vh.reserve(mesh.n_vertices() + mesh.n_edges());
  for (auto v : mesh.vertices()) {
    vh.push_back(out.add_vertex(mesh.point(v)));
    out.set_normal(vh.back(), mesh.normal(v));
  }
  for (auto e : mesh.edges()) {
    const EdgeMidpoint m = midpoint(e);
    vh.push_back(out.add_vertex(ToOpenMesh(m.point)));
    out.set_normal(vh.back(), ToOpenMesh(m.normal));
  }
  const int nv = static_cast<int>(mesh.n_vertices());
  for (auto f : mesh.faces()) {
    // Same vertex order as fv_range (FacePatch): v_k = to-vertex of face halfedge h_k,
    // so h_{k+1} runs from v_k to v_{k+1}.
    std::array<TinMesh::HalfedgeHandle, 3> h;
    std::array<TinMesh::VertexHandle, 3> v, m;
    int k = 0;
    for (auto he : mesh.fh_range(f)) h[k++] = he;
    for (k = 0; k < 3; ++k) {
      v[k] = vh[mesh.to_vertex_handle(h[k]).idx()];
      m[k] = vh[nv + mesh.edge_handle(h[(k + 1) % 3]).idx()];
    }
    // m[0] = m01, m[1] = m12, m[2] = m20.
    out.add_face(v[0], m[0], m[2]);
    out.add_face(m[0], v[1], m[1]);
    out.add_face(m[2], m[1], v[2]);
    out.add_face(m[0], m[1], m[2]);
  }
  if (!options.keep_g1_normals) {
    UpdateVertexNormals(&out);
  } else {
    // Face normals only (vertex normals stay as set).
    for (auto f : out.faces()) out.set_normal(f, out.calc_face_normal(f));
  }
  return out;
}

}  // namespace

TinMesh QuaternarySubdivide(const TinMesh& mesh, const SubdivisionOptions& options) {
  return Subdivide(mesh, options, [&](TinMesh::EdgeHandle e) {
    // The boundary curve depends only on the edge's two vertices and normals, so both
    // neighbouring faces agree on the new vertex.
    const EdgeCurve curve = MakeEdgeCurve(mesh, e);
    return EdgeMidpoint{curve.Point(0.5), curve.Normal(0.5)};
  });
}

TinMesh QuaternarySubdivide(const TinMesh& mesh, const CornerNormals& corners,
                            const SubdivisionOptions& options) {
  return Subdivide(mesh, options, [&](TinMesh::EdgeHandle e) {
    // The curve of the surface with creases: the straight chord on a crease edge, else
    // the boundary curve from the corner normals of the adjacent faces' sector (both
    // faces lie in the same sector at each end, so either face gives the same curve).
    auto heh = mesh.halfedge_handle(e, 0);
    if (!mesh.face_handle(heh).is_valid()) heh = mesh.halfedge_handle(e, 1);
    const Eigen::Vector3d a = ToEigen(mesh.point(mesh.from_vertex_handle(heh)));
    const Eigen::Vector3d b = ToEigen(mesh.point(mesh.to_vertex_handle(heh)));
    const Eigen::Vector3d& n_a = corners.normals[mesh.prev_halfedge_handle(heh).idx()];
    const Eigen::Vector3d& n_b = corners.normals[heh.idx()];
    const EdgeCurve curve = corners.crease_edge[e.idx()] ? EdgeCurve::Straight(a, n_a, b, n_b)
                                                          : EdgeCurve(a, n_a, b, n_b);
    return EdgeMidpoint{curve.Point(0.5), curve.Normal(0.5)};
  });
}

}  // namespace facets
