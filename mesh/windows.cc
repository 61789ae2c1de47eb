#include "mesh/windows.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

namespace facets {
namespace {

void SplitFaces(const std::vector<Eigen::Vector3d>& centres, std::vector<int> faces,
                int max_faces, std::vector<std::vector<int>>* leaves) {
  if (static_cast<int>(faces.size()) <= max_faces) {
    std::sort(faces.begin(), faces.end());
    leaves->push_back(std::move(faces));
    return;
  }
  Eigen::Vector3d lo = centres[faces.front()], hi = lo;
  for (int f : faces) {
    lo = lo.cwiseMin(centres[f]);
    hi = hi.cwiseMax(centres[f]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const auto middle = faces.begin() + faces.size() / 2;
  // Ties broken by face index: the split is deterministic on regular grids.
  std::nth_element(faces.begin(), middle, faces.end(), [&](int a, int b) {
    return centres[a][axis] != centres[b][axis] ? centres[a][axis] < centres[b][axis] : a < b;
  });
  std::vector<int> upper(middle, faces.end());
  faces.erase(middle, faces.end());
  SplitFaces(centres, std::move(faces), max_faces, leaves);
  SplitFaces(centres, std::move(upper), max_faces, leaves);
}

// Core faces plus `rings` rings of faces around them, plus faces whose three vertices
// are already in (notches of one face would leave non-manifold fixed vertices).
std::vector<int> GrowWindow(const TinMesh& mesh, const std::vector<int>& core, int rings) {
  std::vector<char> in_face(mesh.n_faces(), 0), in_vertex(mesh.n_vertices(), 0);
  std::vector<int> faces = core;
  for (int f : core) in_face[f] = 1;
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<int> vertices;
    for (int f : faces) {
      for (auto vh : mesh.fv_range(mesh.face_handle(f))) {
        if (!in_vertex[vh.idx()]) {
          in_vertex[vh.idx()] = 1;
          vertices.push_back(vh.idx());
        }
      }
    }
    for (int v : vertices) {
      for (auto fh : mesh.vf_range(mesh.vertex_handle(v))) {
        if (!in_face[fh.idx()]) {
          in_face[fh.idx()] = 1;
          faces.push_back(fh.idx());
        }
      }
    }
  }
  for (int f : faces) {
    for (auto vh : mesh.fv_range(mesh.face_handle(f))) in_vertex[vh.idx()] = 1;
  }
  for (auto fh : mesh.faces()) {
    if (in_face[fh.idx()]) continue;
    bool all = true;
    for (auto vh : mesh.fv_range(fh)) all = all && in_vertex[vh.idx()];
    if (all) {
      in_face[fh.idx()] = 1;
      faces.push_back(fh.idx());
    }
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

}  // namespace

void WindowPartitionOptions::Check() const {
  if (max_faces < 1) throw std::invalid_argument("windows: max_faces must be >= 1");
  if (margin_rings < 1) throw std::invalid_argument("windows: margin_rings must be >= 1");
}

std::vector<MeshWindow> PartitionIntoWindows(const TinMesh& mesh,
                                             const WindowPartitionOptions& options) {
  std::vector<int> all(mesh.n_faces());
  std::iota(all.begin(), all.end(), 0);
  return PartitionFacesIntoWindows(mesh, std::move(all), options);
}

std::vector<MeshWindow> PartitionFacesIntoWindows(const TinMesh& mesh, std::vector<int> faces,
                                                  const WindowPartitionOptions& options) {
  options.Check();
  const int num_faces = static_cast<int>(mesh.n_faces());
  std::vector<Eigen::Vector3d> centres(num_faces, Eigen::Vector3d::Zero());
  for (int f : faces) {
    if (f < 0 || f >= num_faces) throw std::invalid_argument("windows: face index out of range");
    for (auto vh : mesh.fv_range(mesh.face_handle(f))) centres[f] += ToEigen(mesh.point(vh)) / 3.0;
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  std::vector<std::vector<int>> leaves;
  if (!faces.empty()) SplitFaces(centres, std::move(faces), options.max_faces, &leaves);
  std::vector<int> face_window(num_faces, -1);
  std::vector<MeshWindow> windows(leaves.size());
  for (size_t w = 0; w < leaves.size(); ++w) {
    for (int f : leaves[w]) face_window[f] = static_cast<int>(w);
    windows[w].core_faces = std::move(leaves[w]);
    windows[w].faces = GrowWindow(mesh, windows[w].core_faces, options.margin_rings);
  }
  // Owner of a vertex: the window of its lowest-index face among the partitioned ones
  // (vertices with none stay unowned).
  for (auto vh : mesh.vertices()) {
    int lowest = -1;
    for (auto fh : mesh.vf_range(vh)) {
      if (face_window[fh.idx()] >= 0 && (lowest < 0 || fh.idx() < lowest)) lowest = fh.idx();
    }
    if (lowest >= 0) windows[face_window[lowest]].owned_vertices.push_back(vh.idx());
  }
  return windows;
}

std::vector<int> FacesNearVertices(const TinMesh& mesh, const std::vector<char>& seeds, int rings) {
  if (seeds.size() != mesh.n_vertices()) throw std::invalid_argument("windows: one seed flag per vertex");
  std::vector<char> near = seeds;
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<char> grown = near;
    for (auto vh : mesh.vertices()) {
      if (!near[vh.idx()]) continue;
      for (auto nh : mesh.vv_range(vh)) grown[nh.idx()] = 1;
    }
    near = std::move(grown);
  }
  std::vector<int> faces;
  for (auto fh : mesh.faces()) {
    for (auto vh : mesh.fv_range(fh)) {
      if (near[vh.idx()]) {
        faces.push_back(fh.idx());
        break;
      }
    }
  }
  return faces;
}

std::vector<std::vector<int>> IndependentWindowGroups(const TinMesh& mesh,
                                                      const std::vector<MeshWindow>& windows) {
  std::vector<std::vector<int>> vertex_windows(mesh.n_vertices());
  for (size_t w = 0; w < windows.size(); ++w) {
    for (int f : windows[w].faces) {
      for (auto vh : mesh.fv_range(mesh.face_handle(f))) {
        auto& list = vertex_windows[vh.idx()];
        if (list.empty() || list.back() != static_cast<int>(w)) list.push_back(static_cast<int>(w));
      }
    }
  }
  std::vector<int> colour(windows.size(), -1);
  std::vector<std::vector<int>> groups;
  for (size_t w = 0; w < windows.size(); ++w) {
    std::vector<char> used(groups.size() + 1, 0);
    for (int f : windows[w].faces) {
      for (auto vh : mesh.fv_range(mesh.face_handle(f))) {
        for (int other : vertex_windows[vh.idx()]) {
          if (colour[other] >= 0) used[colour[other]] = 1;
        }
      }
    }
    int c = 0;
    while (used[c]) ++c;
    colour[w] = c;
    if (c == static_cast<int>(groups.size())) groups.emplace_back();
    groups[c].push_back(static_cast<int>(w));
  }
  return groups;
}

WindowMesh ExtractWindowMesh(const TinMesh& mesh, const MeshWindow& window) {
  WindowMesh out;
  std::vector<char> in_window(mesh.n_faces(), 0);
  for (int f : window.faces) in_window[f] = 1;
  std::vector<int> local(mesh.n_vertices(), -1);
  for (int f : window.faces) {
    std::vector<TinMesh::VertexHandle> corners;
    for (auto vh : mesh.fv_range(mesh.face_handle(f))) {
      if (local[vh.idx()] < 0) {
        local[vh.idx()] = static_cast<int>(out.global_vertex.size());
        out.global_vertex.push_back(vh.idx());
        auto added = out.mesh.add_vertex(mesh.point(vh));
        out.mesh.set_normal(added, mesh.normal(vh));
      }
      corners.push_back(out.mesh.vertex_handle(local[vh.idx()]));
    }
    if (!out.mesh.add_face(corners).is_valid()) {
      throw std::runtime_error("ExtractWindowMesh: face " + std::to_string(f) +
                               " cannot be added (non-manifold window)");
    }
    out.global_face.push_back(f);
  }
  out.fixed.assign(out.global_vertex.size(), false);
  for (size_t v = 0; v < out.global_vertex.size(); ++v) {
    for (auto fh : mesh.vf_range(mesh.vertex_handle(out.global_vertex[v]))) {
      if (!in_window[fh.idx()]) out.fixed[v] = true;
    }
  }
  for (int v : window.owned_vertices) out.owned_local.push_back(local[v]);
  out.mesh.update_face_normals();
  return out;
}

}  // namespace facets
