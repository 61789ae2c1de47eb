#include "mesh/tin.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace facets {

void StartGridOptions::Check() const {
  if (!(spacing > 0.0) || !std::isfinite(spacing)) {
    throw std::invalid_argument("StartGridOptions: spacing must be positive and finite");
  }
  if (!(max.x() > min.x()) || !(max.y() > min.y()) || !min.allFinite() || !max.allFinite()) {
    throw std::invalid_argument("StartGridOptions: need finite min < max in x and y");
  }
  if (!std::isfinite(plane_height)) {
    throw std::invalid_argument("StartGridOptions: plane_height is not finite");
  }
  const double cells = ((max.x() - min.x()) / spacing) * ((max.y() - min.y()) / spacing);
  if (cells > 1e8) throw std::invalid_argument("StartGridOptions: more than 1e8 grid cells");
}

TinMesh MakeStartGrid(const StartGridOptions& options) {
  options.Check();
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
  using Tds = CGAL::Triangulation_data_structure_2<Vb>;
  using Delaunay = CGAL::Delaunay_triangulation_2<Kernel, Tds>;

  const Eigen::Vector2d range = options.max - options.min;
  const int nx = std::max(1, static_cast<int>(std::ceil(range.x() / options.spacing - 1e-9)));
  const int ny = std::max(1, static_cast<int>(std::ceil(range.y() / options.spacing - 1e-9)));
  std::vector<std::pair<Kernel::Point_2, int>> points;
  points.reserve(static_cast<size_t>(nx + 1) * (ny + 1));
  TinMesh mesh;
  std::vector<TinMesh::VertexHandle> handles;
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      const double x = i == nx ? options.max.x() : options.min.x() + range.x() * i / nx;
      const double y = j == ny ? options.max.y() : options.min.y() + range.y() * j / ny;
      const double z = options.height ? options.height(x, y) : options.plane_height;
      if (!std::isfinite(z)) {
        std::ostringstream msg;
        msg << "MakeStartGrid: height function is not finite at (" << x << ", " << y << ")";
        throw std::invalid_argument(msg.str());
      }
      const int index = static_cast<int>(handles.size());
      handles.push_back(mesh.add_vertex(TinMesh::Point(x, y, z)));
      points.emplace_back(Kernel::Point_2(x, y), index);
    }
  }
  Delaunay dt;
  dt.insert(points.begin(), points.end());
  // Deterministic face order: sort by the (sorted) vertex triple.
  std::vector<std::array<int, 3>> faces;
  faces.reserve(dt.number_of_faces());
  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f) {
    std::array<int, 3> t = {f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};
    // Rotate so the smallest index comes first (keeps the CCW order).
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
    faces.push_back(t);
  }
  std::sort(faces.begin(), faces.end());
  for (const auto& t : faces) mesh.add_face(handles[t[0]], handles[t[1]], handles[t[2]]);
  UpdateVertexNormals(&mesh);
  return mesh;
}

TinMesh LoadStartMesh(const std::string& path) {
  if (!std::filesystem::exists(path)) {
    throw std::runtime_error("LoadStartMesh: " + path + ": file does not exist");
  }
  TinMesh mesh;
  OpenMesh::IO::Options opt;
  if (!OpenMesh::IO::read_mesh(mesh, path, opt)) {
    throw std::runtime_error("LoadStartMesh: " + path +
                             ": unreadable (unknown format or malformed mesh)");
  }
  if (mesh.n_faces() == 0) {
    throw std::runtime_error("LoadStartMesh: " + path + ": contains no triangles");
  }
  for (auto vh : mesh.vertices()) {
    const auto& p = mesh.point(vh);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      throw std::runtime_error("LoadStartMesh: " + path + ": vertex " +
                               std::to_string(vh.idx()) + " is not finite");
    }
  }
  UpdateVertexNormals(&mesh);
  return mesh;
}

void UpdateVertexNormals(TinMesh* mesh) {
  for (auto fh : mesh->faces()) {
    auto it = mesh->cfv_iter(fh);
    const auto p0 = mesh->point(*it);
    const auto p1 = mesh->point(*++it);
    const auto p2 = mesh->point(*++it);
    auto n = OpenMesh::cross(p1 - p0, p2 - p0);
    const double len = n.norm();
    mesh->set_normal(fh, len > 0.0 ? n / len : TinMesh::Normal(0, 0, 0));
  }
  // Mean of the face normals weighted by the face's corner angle at the vertex
  // (Thuermer & Wuethrich): unlike the plain mean it does not depend on how the
  // neighbourhood happens to be triangulated, so a ridge vertex of a symmetric roof
  // gets the vertical normal whatever the diagonals of the grid.
  for (auto vh : mesh->vertices()) {
    TinMesh::Normal sum(0, 0, 0);
    const auto p = mesh->point(vh);
    for (auto heh : mesh->voh_range(vh)) {
      const auto fh = mesh->face_handle(heh);
      if (!fh.is_valid()) continue;
      const auto e1 = mesh->point(mesh->to_vertex_handle(heh)) - p;
      const auto e2 = mesh->point(mesh->from_vertex_handle(mesh->prev_halfedge_handle(heh))) - p;
      const double angle = std::atan2(OpenMesh::cross(e1, e2).norm(), OpenMesh::dot(e1, e2));
      sum += angle * mesh->normal(fh);
    }
    const double len = sum.norm();
    if (len > 0.0) mesh->set_normal(vh, sum / len);
  }
}

G1Patch FacePatch(const TinMesh& mesh, TinMesh::FaceHandle fh) {
  Eigen::Vector3d x[3], n[3];
  int k = 0;
  for (auto vh : mesh.fv_range(fh)) {
    x[k] = ToEigen(mesh.point(vh));
    n[k] = ToEigen(mesh.normal(vh));
    ++k;
  }
  return G1Patch(x[0], x[1], x[2], n[0], n[1], n[2]);
}

std::vector<std::array<int, 3>> FaceVertices(const TinMesh& mesh) {
  std::vector<std::array<int, 3>> out(mesh.n_faces());
  for (auto fh : mesh.faces()) {
    int k = 0;
    for (auto vh : mesh.fv_range(fh)) out[fh.idx()][k++] = vh.idx();
  }
  return out;
}

std::vector<G1Patch> BuildPatches(const TinMesh& mesh) {
  std::vector<G1Patch> patches(mesh.n_faces());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.n_faces(), 1024),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t f = r.begin(); f != r.end(); ++f) {
                        patches[f] = FacePatch(mesh, mesh.face_handle(static_cast<int>(f)));
                      }
                    });
  return patches;
}

EdgeCurve MakeEdgeCurve(const TinMesh& mesh, TinMesh::EdgeHandle eh) {
  const auto heh = mesh.halfedge_handle(eh, 0);
  const auto va = mesh.from_vertex_handle(heh), vb = mesh.to_vertex_handle(heh);
  return EdgeCurve(ToEigen(mesh.point(va)), ToEigen(mesh.normal(va)), ToEigen(mesh.point(vb)),
                   ToEigen(mesh.normal(vb)));
}

}  // namespace facets
