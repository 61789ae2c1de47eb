#include "refine/unseen_lips.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "mesh/principal_axes.h"
#include "mesh/surface_validity.h"

namespace facets {
namespace {

Eigen::Vector3d Point(const TinMesh& mesh, int v) { return ToEigen(mesh.point(mesh.vertex_handle(v))); }
Eigen::Vector3d Normal(const TinMesh& mesh, int v) { return ToEigen(mesh.normal(mesh.vertex_handle(v))); }

// Connected groups of the flagged vertices (edges of the TIN between them).
std::vector<std::vector<int>> ConnectedGroups(const TinMesh& mesh, const std::vector<bool>& flagged) {
  std::vector<std::vector<int>> groups;
  std::vector<bool> taken(flagged.size(), false);
  for (size_t seed = 0; seed < flagged.size(); ++seed) {
    if (!flagged[seed] || taken[seed]) continue;
    std::vector<int> group{static_cast<int>(seed)};
    taken[seed] = true;
    for (size_t k = 0; k < group.size(); ++k) {
      for (auto w : mesh.vv_range(mesh.vertex_handle(group[k]))) {
        if (flagged[w.idx()] && !taken[w.idx()]) {
          taken[w.idx()] = true;
          group.push_back(w.idx());
        }
      }
    }
    groups.push_back(std::move(group));
  }
  return groups;
}

// Vertices within `rings` edge rings of the sources (the sources included).
std::vector<int> WithinRings(const TinMesh& mesh, const std::vector<int>& sources, int rings) {
  std::unordered_map<int, int> ring;
  std::vector<int> order;
  for (int v : sources) {
    if (ring.emplace(v, 0).second) order.push_back(v);
  }
  for (size_t k = 0; k < order.size(); ++k) {
    const int r = ring[order[k]];
    if (r == rings) continue;
    for (auto w : mesh.vv_range(mesh.vertex_handle(order[k]))) {
      if (ring.emplace(w.idx(), r + 1).second) order.push_back(w.idx());
    }
  }
  return order;
}

struct Plane {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();
  double rms = 0.0;
  int support = 0;
};

// Total-least-squares plane, refitted three times without the points beyond 3 robust
// sigmas (MAD) of the signed distances: a wall's neighbourhood holds eaves and the lip's
// own seen top, which must not tilt the wall.
Plane FitRobustPlane(std::vector<Eigen::Vector3d> points) {
  Plane plane;
  for (int round = 0; round < 4 && points.size() >= 3; ++round) {
    const PrincipalAxes fit = FitPrincipalAxes(points);
    const Eigen::Vector3d centre = fit.centre;
    plane.centre = centre;
    plane.normal = fit.Normal();
    double sum = 0.0;
    std::vector<double> r;
    for (const auto& p : points) {
      r.push_back(plane.normal.dot(p - centre));
      sum += r.back() * r.back();
    }
    plane.rms = std::sqrt(sum / points.size());
    plane.support = static_cast<int>(points.size());
    if (round == 3) break;
    std::vector<double> sorted = r;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median = sorted[sorted.size() / 2];
    for (double& x : sorted) x = std::abs(x - median);
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double cut = std::max(3.0 * 1.4826 * sorted[sorted.size() / 2], 1e-6);
    std::vector<Eigen::Vector3d> kept;
    for (size_t i = 0; i < points.size(); ++i) {
      if (std::abs(r[i] - median) <= cut) kept.push_back(points[i]);
    }
    if (kept.size() == points.size() || kept.size() < 3) break;
    points = std::move(kept);
  }
  return plane;
}

// The lip grown from the group's vertices off the plane, each side by its own rule
// (FindUnseenLips). not free: it reached the TIN's border or grew beyond max_lip.
struct Lip {
  std::vector<int> vertices;
  int in_front = 0;
  bool free = true;
};
Lip GrowLip(const TinMesh& mesh, const std::vector<int>& group, const std::vector<int>& views,
            const std::vector<bool>& claimed, const Plane& plane, const LipFoldOptions& options) {
  Lip lip;
  auto off = [&](int v) { return plane.normal.dot(Point(mesh, v) - plane.centre); };
  double reach = 0.0, foot = 1e300;
  for (int v : group) {
    const double s = off(v);
    if (std::abs(s) <= options.front_tolerance || claimed[v]) continue;
    lip.vertices.push_back(v);
    reach = std::max(reach, std::abs(s));
    if (s > 0.0) foot = std::min(foot, Point(mesh, v).z());
  }
  const double max_off = options.reach_factor * reach + options.front_tolerance;
  std::unordered_set<int> in(lip.vertices.begin(), lip.vertices.end());
  for (size_t k = 0; k < lip.vertices.size(); ++k) {
    const int v = lip.vertices[k];
    if (mesh.is_boundary(mesh.vertex_handle(v)) || static_cast<int>(lip.vertices.size()) > options.max_lip) {
      lip.free = false;
      return lip;
    }
    const bool front = off(v) > 0.0;
    for (auto w : mesh.vv_range(mesh.vertex_handle(v))) {
      if (in.count(w.idx()) || claimed[w.idx()]) continue;
      const double s = off(w.idx());
      if ((s > 0.0) != front || std::abs(s) <= options.front_tolerance || std::abs(s) > max_off) continue;
      if (front && ToEigen(mesh.point(w)).z() < foot - options.front_tolerance) continue;
      if (!front && views[w.idx()] >= options.wall_min_views) continue;
      in.insert(w.idx());
      lip.vertices.push_back(w.idx());
    }
  }
  for (int v : lip.vertices) lip.in_front += off(v) > 0.0 ? 1 : 0;
  return lip;
}

}  // namespace

LipSearch FindUnseenLips(const TinMesh& mesh, const std::vector<int>& views, const LipFoldOptions& options) {
  if (views.size() != mesh.n_vertices()) {
    throw std::invalid_argument("FindUnseenLips: one view count per vertex needed");
  }
  LipSearch search;
  std::vector<bool> unseen(mesh.n_vertices(), false);
  for (auto v : mesh.vertices()) {
    unseen[v.idx()] = views[v.idx()] == 0 && !mesh.is_boundary(v) && mesh.valence(v) > 0 &&
                      mesh.normal(v)[2] < options.max_normal_z;
  }
  std::vector<bool> claimed(mesh.n_vertices(), false);
  for (const std::vector<int>& group : ConnectedGroups(mesh, unseen)) {
    if (static_cast<int>(group.size()) < options.min_group) continue;
    ++search.groups;
    // Which way the lip leans out: the wall it hangs from faces the same way.
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int v : group) mean += Normal(mesh, v);
    mean /= static_cast<double>(group.size());
    const Eigen::Vector2d out(mean.x(), mean.y());
    if (out.norm() < options.min_horizontal) {
      ++search.no_wall;
      continue;
    }
    const Eigen::Vector2d facing = out.normalized();
    std::vector<Eigen::Vector3d> wall;
    for (int v : WithinRings(mesh, group, options.wall_rings)) {
      if (views[v] < options.wall_min_views || claimed[v]) continue;
      const Eigen::Vector3d n = Normal(mesh, v);
      const Eigen::Vector2d h(n.x(), n.y());
      if (std::abs(n.z()) > options.wall_max_normal_z || h.norm() < 1e-9) continue;
      if (h.normalized().dot(facing) < options.wall_min_facing) continue;
      wall.push_back(Point(mesh, v));
    }
    if (static_cast<int>(wall.size()) < options.min_wall_vertices) {
      ++search.no_wall;
      continue;
    }
    Plane plane = FitRobustPlane(wall);
    if (Eigen::Vector2d(plane.normal.x(), plane.normal.y()).dot(facing) < 0.0) plane.normal = -plane.normal;
    if (plane.support < options.min_wall_vertices || plane.rms > options.max_plane_rms ||
        std::abs(plane.normal.z()) > options.wall_max_normal_z) {
      ++search.no_wall;
      continue;
    }
    const Lip lip = GrowLip(mesh, group, views, claimed, plane, options);
    if (!lip.free) {
      ++search.not_free;
      continue;
    }
    if (lip.vertices.empty()) continue;  // the group lies on the wall: an unseen part of it
    for (int v : lip.vertices) claimed[v] = true;
    UnseenLip found;
    found.vertices = lip.vertices;
    found.in_front = lip.in_front;
    found.plane_point = plane.centre;
    found.plane_normal = plane.normal;
    found.support = plane.support;
    found.plane_rms = plane.rms;
    search.lips.push_back(std::move(found));
  }
  return search;
}

LipFold LayLipOntoWall(TinMesh* mesh, const UnseenLip& lip, int iterations) {
  LipFold fold;
  for (int v : lip.vertices) fold.centre += Point(*mesh, v);
  if (!lip.vertices.empty()) fold.centre /= static_cast<double>(lip.vertices.size());
  fold.normal = lip.plane_normal;
  fold.support = lip.support;
  fold.plane_rms = lip.plane_rms;
  fold.vertices = static_cast<int>(lip.vertices.size());
  fold.in_front = lip.in_front;
  // Tutte's embedding in the plane's coordinates (e1 horizontal along the wall).
  const Eigen::Vector3d e1 = Eigen::Vector3d::UnitZ().cross(lip.plane_normal).normalized();
  const Eigen::Vector3d e2 = lip.plane_normal.cross(e1);
  const auto& verts = lip.vertices;
  std::unordered_map<int, int> index;
  for (size_t i = 0; i < verts.size(); ++i) index[verts[i]] = static_cast<int>(i);
  auto project = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d(e1.dot(p - lip.plane_point), e2.dot(p - lip.plane_point));
  };
  std::vector<Eigen::Vector2d> uv(verts.size());
  std::vector<std::vector<int>> free_neighbours(verts.size());
  std::vector<Eigen::Vector2d> held_sum(verts.size(), Eigen::Vector2d::Zero());
  std::vector<int> degree(verts.size(), 0);
  for (size_t i = 0; i < verts.size(); ++i) {
    uv[i] = project(Point(*mesh, verts[i]));
    for (auto w : mesh->vv_range(mesh->vertex_handle(verts[i]))) {
      ++degree[i];
      auto it = index.find(w.idx());
      if (it != index.end()) {
        free_neighbours[i].push_back(it->second);
      } else {
        held_sum[i] += project(ToEigen(mesh->point(w)));
      }
    }
  }
  std::vector<Eigen::Vector2d> next(verts.size());
  for (int it = 0; it < iterations; ++it) {
    double change = 0.0;
    for (size_t i = 0; i < verts.size(); ++i) {
      Eigen::Vector2d sum = held_sum[i];
      for (int j : free_neighbours[i]) sum += uv[j];
      next[i] = sum / degree[i];
      change = std::max(change, (next[i] - uv[i]).norm());
    }
    uv.swap(next);
    if (change < 1e-9) break;
  }
  for (size_t i = 0; i < verts.size(); ++i) {
    const Eigen::Vector3d p = lip.plane_point + uv[i].x() * e1 + uv[i].y() * e2;
    fold.max_move = std::max(fold.max_move, (p - Point(*mesh, verts[i])).norm());
    mesh->set_point(mesh->vertex_handle(verts[i]), ToOpenMesh(p));
  }
  return fold;
}

int FlattenFoldedRim(TinMesh* mesh, const UnseenLip& lip, const std::vector<bool>& folded_before, double reach,
                     int rounds) {
  const std::unordered_set<int> in_lip(lip.vertices.begin(), lip.vertices.end());
  int projected = 0;
  for (int round = 0; round < rounds; ++round) {
    const std::vector<bool> folded = FoldedFaces(*mesh);
    int moved = 0;
    for (auto fh : mesh->faces()) {
      if (!folded[fh.idx()] || folded_before[fh.idx()]) continue;
      for (auto vh : mesh->fv_range(fh)) {
        if (in_lip.count(vh.idx()) > 0) continue;
        const Eigen::Vector3d p = ToEigen(mesh->point(vh));
        const double d = (p - lip.plane_point).dot(lip.plane_normal);
        if (std::abs(d) < 1e-9 || std::abs(d) > reach) continue;
        mesh->set_point(vh, ToOpenMesh(Eigen::Vector3d(p - d * lip.plane_normal)));
        ++moved;
      }
    }
    projected += moved;
    if (moved == 0) break;
  }
  return projected;
}

LipFoldReport FoldUnseenLipsOntoWalls(TinMesh* mesh, const std::vector<int>& views, const LipFoldOptions& options) {
  const LipSearch search = FindUnseenLips(*mesh, views, options);
  LipFoldReport report;
  report.groups = search.groups;
  report.no_wall = search.no_wall;
  report.not_free = search.not_free;
  for (const UnseenLip& lip : search.lips) {
    report.lips.push_back(LayLipOntoWall(mesh, lip, options.embedding_iterations));
    ++report.folded;
    report.moved += report.lips.back().vertices;
    report.max_move = std::max(report.max_move, report.lips.back().max_move);
  }
  return report;
}

}  // namespace facets
