#include "mesh/creases.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "mesh/local_ops.h"
#include "mesh/principal_axes.h"

namespace facets {
namespace {

Eigen::Vector3d AreaFaceNormal(const TinMesh& mesh, TinMesh::FaceHandle fh) {
  auto it = mesh.cfv_iter(fh);
  const Eigen::Vector3d p0 = ToEigen(mesh.point(*it));
  const Eigen::Vector3d p1 = ToEigen(mesh.point(*++it));
  const Eigen::Vector3d p2 = ToEigen(mesh.point(*++it));
  return (p1 - p0).cross(p2 - p0);
}

// A face is a cap (no area: its corners on one line) when its height over its longest
// edge is below this fraction of that edge (NoArea, mesh/local_ops.h).
constexpr double kCapHeight = 1e-3;

Eigen::Vector3d UnitFaceNormal(const TinMesh& mesh, TinMesh::FaceHandle fh) {
  const Eigen::Vector3d n = AreaFaceNormal(mesh, fh);
  const double len = n.norm();
  return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

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

namespace {

// Straight runs of a set of crease vertices: lines through two of its vertices (drawn
// at random with a fixed seed, so runs are reproducible), the one with the most
// vertices within max_offset edges in one stretch without a gap of more than 1.5
// edges; its vertices leave the set and the next line is sought, until no stretch
// spans min_edges edges. A straight set gives one run.
std::vector<std::vector<int>> StraightRuns(const TinMesh& mesh, std::vector<int> remaining, double h,
                                           double max_offset, int min_edges) {
  std::vector<std::vector<int>> runs;
  std::mt19937 random(12345);
  auto point = [&](int v) { return ToEigen(mesh.point(mesh.vertex_handle(v))); };
  const int trials = 200;
  while (remaining.size() >= 3) {
    std::vector<int> best;
    double best_span = 0.0;
    std::uniform_int_distribution<size_t> pick(0, remaining.size() - 1);
    std::vector<std::pair<double, int>> on_line;
    for (int trial = 0; trial < trials; ++trial) {
      const Eigen::Vector3d a = point(remaining[pick(random)]), b = point(remaining[pick(random)]);
      const double length = (b - a).norm();
      if (length < 2.0 * h) continue;
      const Eigen::Vector3d dir = (b - a) / length;
      on_line.clear();
      for (int v : remaining) {
        const Eigen::Vector3d d = point(v) - a;
        if ((d - d.dot(dir) * dir).norm() <= max_offset * h) on_line.emplace_back(d.dot(dir), v);
      }
      if (on_line.size() <= best.size()) continue;
      std::sort(on_line.begin(), on_line.end());
      size_t begin = 0;
      for (size_t i = 1; i <= on_line.size(); ++i) {
        if (i < on_line.size() && on_line[i].first - on_line[i - 1].first <= 1.5 * h) continue;
        if (i - begin > best.size()) {
          best.clear();
          for (size_t k = begin; k < i; ++k) best.push_back(on_line[k].second);
          best_span = on_line[i - 1].first - on_line[begin].first;
        }
        begin = i;
      }
    }
    if (best.size() < 3 || best_span < min_edges * h * 0.9) break;
    std::vector<int> rest;
    std::sort(best.begin(), best.end());
    for (int v : remaining) {
      if (!std::binary_search(best.begin(), best.end(), v)) rest.push_back(v);
    }
    remaining = std::move(rest);
    runs.push_back(std::move(best));
  }
  return runs;
}

}  // namespace

StraightenReport StraightenCreaseChains(TinMesh* mesh, const std::vector<bool>& crease_edge, CreaseLines lines,
                                        int min_edges, double max_offset) {
  StraightenReport report;
  const double crease_min_deg = 10.0;  // the two side planes must meet at least at this angle
  // The side planes are fitted 1-3 edges from the component's line: nearer than one
  // edge the regularisation still rounds the crease.
  const double side_near = 1.0, side_far = 3.0;
  const int nv = static_cast<int>(mesh->n_vertices());
  std::vector<int> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<bool> on_crease(nv, false);
  for (auto eh : mesh->edges()) {
    if (!crease_edge[eh.idx()]) continue;
    const int a = mesh->to_vertex_handle(mesh->halfedge_handle(eh, 0)).idx();
    const int b = mesh->from_vertex_handle(mesh->halfedge_handle(eh, 0)).idx();
    on_crease[a] = on_crease[b] = true;
    parent[Find(parent, a)] = Find(parent, b);
  }
  // A zigzag's step edges bend less than its runs and may miss the crease angle: crease
  // vertices joined by any edge belong to one set.
  for (auto eh : mesh->edges()) {
    const int a = mesh->to_vertex_handle(mesh->halfedge_handle(eh, 0)).idx();
    const int b = mesh->from_vertex_handle(mesh->halfedge_handle(eh, 0)).idx();
    if (on_crease[a] && on_crease[b]) parent[Find(parent, a)] = Find(parent, b);
  }
  std::vector<std::vector<int>> members(nv);
  for (int v = 0; v < nv; ++v) {
    if (on_crease[v]) members[Find(parent, v)].push_back(v);
  }
  std::vector<double> edge_sum(nv, 0.0);
  std::vector<int> edge_count(nv, 0);
  for (auto eh : mesh->edges()) {
    if (!crease_edge[eh.idx()]) continue;
    const int root = Find(parent, mesh->to_vertex_handle(mesh->halfedge_handle(eh, 0)).idx());
    edge_sum[root] += mesh->calc_edge_length(eh);
    ++edge_count[root];
  }
  auto point = [&](int v) { return ToEigen(mesh->point(mesh->vertex_handle(v))); };
  // A building's creases form one web (eaves, ridges, wall corners joined at their
  // ends): it is cut into straight runs first, and each run is a candidate line.
  struct Candidate {
    std::vector<int> vertices;
    double h;
    bool whole_set;  // the set is one straight run
  };
  std::vector<Candidate> candidates;
  for (int root = 0; root < nv; ++root) {
    if (members[root].empty()) continue;
    ++report.sets;
    if (edge_count[root] < min_edges) {
      ++report.too_small;
      continue;
    }
    const double h = edge_sum[root] / edge_count[root];
    std::vector<std::vector<int>> runs = StraightRuns(*mesh, members[root], h, max_offset, min_edges);
    const bool whole = runs.size() == 1 && runs[0].size() == members[root].size();
    for (std::vector<int>& run : runs) candidates.push_back({std::move(run), h, whole});
  }
  report.lines = static_cast<int>(candidates.size());
  for (const Candidate& candidate : candidates) {
    const double h = candidate.h;
    // Least-squares line of the run's vertices; vertices farther than the offset are
    // dropped and the line refitted.
    std::vector<int> kept = candidate.vertices;
    Eigen::Vector3d centre, dir;
    for (int round = 0; round < 3; ++round) {
      if (kept.size() < 3) break;
      std::vector<Eigen::Vector3d> points;
      for (int v : kept) points.push_back(point(v));
      const PrincipalAxes fit = FitPrincipalAxes(points);
      centre = fit.centre;
      dir = fit.Direction();
      std::vector<int> next;
      for (int v : kept) {
        const Eigen::Vector3d d = point(v) - centre;
        if ((d - d.dot(dir) * dir).norm() <= max_offset * h) next.push_back(v);
      }
      if (next.size() == kept.size()) break;
      kept = std::move(next);
    }
    if (kept.size() < 3) {
      ++report.too_small;
      continue;
    }
    auto along = [&](int v) { return (point(v) - centre).dot(dir); };
    auto off = [&](int v) {
      const Eigen::Vector3d d = point(v) - centre;
      return (d - d.dot(dir) * dir).norm();
    };
    int first = kept.front();
    double t_max = along(first);
    for (int v : kept) {
      if (along(v) < along(first)) first = v;
      t_max = std::max(t_max, along(v));
    }
    if (t_max - along(first) < min_edges * h * 0.9) {
      ++report.too_short;
      continue;
    }
    const double t_min = along(first);
    // The vertices of a zigzag lie mostly on one side of the true crease, so their line
    // is off by up to half an edge: the line is the intersection of the planes fitted to
    // the surface on either side (1-3 edges away), when they meet within one edge of
    // it and run within 20 degrees of it.
    Eigen::Vector3d mean_normal = Eigen::Vector3d::Zero();
    for (int v : kept) mean_normal += ToEigen(mesh->normal(mesh->vertex_handle(v)));
    const Eigen::Vector3d side_axis = mean_normal.cross(dir).normalized();
    std::vector<Eigen::Vector3d> side_points[2];
    // Along the whole line; for a run cut from a web not within an edge of its ends,
    // where the other creases of the web and their faces begin.
    const double side_from = candidate.whole_set ? t_min - 0.5 * h : t_min + h;
    const double side_to = candidate.whole_set ? t_max + 0.5 * h : t_max - h;
    for (auto vh : mesh->vertices()) {
      const Eigen::Vector3d d = ToEigen(mesh->point(vh)) - centre;
      const double t = d.dot(dir), s = d.dot(side_axis);
      if (t < side_from || t > side_to || std::abs(s) < side_near * h || std::abs(s) > side_far * h) continue;
      // Near the crease only: the slab of side distances also holds surface far along
      // the normal (the ground under an eave, the roof above a wall's foot).
      if ((d - t * dir).norm() > 1.5 * side_far * h) continue;
      side_points[s > 0.0 ? 1 : 0].push_back(d);
    }
    bool planes = side_points[0].size() >= 4 && side_points[1].size() >= 4;
    Eigen::Vector3d plane_normal[2], plane_centre[2];
    for (int k = 0; k < 2 && planes; ++k) {
      // Planar sides only: rms distance to the plane within a tenth of an edge, after
      // points off it (another roof face past a hip line's end, a wall below an eave)
      // are dropped, as long as three quarters of them stay.
      std::vector<Eigen::Vector3d> on_plane = side_points[k];
      double rms = 0.0;
      for (int round = 0; round < 3; ++round) {
        const PrincipalAxes fit = FitPrincipalAxes(on_plane);
        plane_centre[k] = fit.centre;
        plane_normal[k] = fit.Normal();
        rms = std::sqrt(std::max(0.0, fit.eigenvalues(0)) / on_plane.size());
        if (rms <= 0.1 * h) break;
        std::vector<Eigen::Vector3d> closer;
        for (const auto& q : on_plane) {
          if (std::abs((q - plane_centre[k]).dot(plane_normal[k])) <= std::max(2.0 * rms, 0.1 * h)) closer.push_back(q);
        }
        if (closer.size() < 4 || closer.size() == on_plane.size() || 4 * closer.size() < 3 * side_points[k].size()) break;
        on_plane = std::move(closer);
      }
      planes = rms <= 0.1 * h;
    }
    if (!planes) {
      ++report.sides_not_planar;
      continue;
    }
    if (lines != CreaseLines::kAll) {
      const double min_roof_nz = std::cos(kSteepCreaseSideDeg * M_PI / 180.0);
      const bool steep = std::abs(plane_normal[0].z()) < min_roof_nz || std::abs(plane_normal[1].z()) < min_roof_nz;
      if (steep != (lines == CreaseLines::kSteep)) {
        ++report.other_kind;
        continue;
      }
    }
    Eigen::Vector3d line_dir = plane_normal[0].cross(plane_normal[1]);
    if (line_dir.norm() < std::sin(crease_min_deg * M_PI / 180.0)) {
      ++report.sides_not_meeting;
      continue;
    }
    line_dir.normalize();
    if (line_dir.dot(dir) < 0.0) line_dir = -line_dir;
    if (line_dir.dot(dir) < std::cos(20.0 * M_PI / 180.0)) {
      ++report.sides_not_meeting;
      continue;
    }
    // The point of the line nearest the old centre: both plane equations plus t = 0.
    Eigen::Matrix3d a;
    a.row(0) = plane_normal[0].transpose();
    a.row(1) = plane_normal[1].transpose();
    a.row(2) = line_dir.transpose();
    const Eigen::Vector3d rhs(plane_normal[0].dot(plane_centre[0]), plane_normal[1].dot(plane_centre[1]), 0.0);
    const Eigen::Vector3d line_point = a.colPivHouseholderQr().solve(rhs);
    if (line_point.norm() > h) {
      ++report.sides_not_meeting;
      continue;
    }
    centre += line_point;
    dir = line_dir;
    ++report.components;
    // From the vertex nearest the line in the middle of the component, through the mesh
    // to both ends, one and a half edges beyond the component's crease vertices (the crease may
    // fade out before the ridge ends).
    double t_end = -std::numeric_limits<double>::infinity();
    double t_start = std::numeric_limits<double>::infinity();
    for (int v : kept) {
      t_start = std::min(t_start, along(v));
      t_end = std::max(t_end, along(v));
    }
    const double t_mid = 0.5 * (t_start + t_end);
    int middle = -1;
    for (auto vh : mesh->vertices()) {
      const double t = along(vh.idx());
      if (std::abs(t - t_mid) > 0.5 * h || off(vh.idx()) > max_offset * h) continue;
      if (middle < 0 || off(vh.idx()) < off(middle)) middle = vh.idx();
    }
    if (middle < 0) {
      ++report.no_chain;
      continue;
    }
    std::vector<int> chain;
    for (int sense : {-1, 1}) {
      std::vector<int> half{middle};
      // A run cut from a web ends where other creases begin: its chain stops half an
      // edge short of the junction, whose vertices the runs would pull apart.
      const double beyond = candidate.whole_set ? 1.5 * h : -0.5 * h;
      const double limit = sense > 0 ? t_end + beyond : t_start - beyond;
      while (true) {
        const double t = along(half.back());
        int best = -1;
        // A step across the line's direction (a grid edge nearly perpendicular to it)
        // only when no neighbour advances by a third of an edge.
        for (double advance : {h / 3.0, 0.1 * h}) {
          for (auto w : mesh->vv_range(mesh->vertex_handle(half.back()))) {
            const double tw = along(w.idx());
            if (sense * (tw - t) < advance || sense * (tw - limit) > 0.0 || off(w.idx()) > max_offset * h) continue;
            if (best < 0 || off(w.idx()) < off(best)) best = w.idx();
          }
          if (best >= 0) break;
        }
        if (best < 0) break;
        half.push_back(best);
      }
      if (sense < 0) {
        chain.assign(half.rbegin(), half.rend());
      } else {
        chain.insert(chain.end(), half.begin() + 1, half.end());
      }
    }
    if (chain.size() < 3) {
      ++report.no_chain;
      continue;
    }
    // Move, and undo the component's moves when a face turns over.
    std::vector<int> faces;
    std::vector<Eigen::Vector3d> normal_before;
    for (int v : chain) {
      for (auto fh : mesh->vf_range(mesh->vertex_handle(v))) faces.push_back(fh.idx());
    }
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    for (int f : faces) normal_before.push_back(UnitFaceNormal(*mesh, mesh->face_handle(f)));
    auto normal_before_of = [&](TinMesh::FaceHandle fh) {
      const auto it = std::lower_bound(faces.begin(), faces.end(), fh.idx());
      return it != faces.end() && *it == fh.idx() ? normal_before[it - faces.begin()] : Eigen::Vector3d::Zero().eval();
    };
    // A chain that zigzags tightly across the line (a fine TIN over a ridge, issue 7's
    // thorough runs) often has one vertex whose move would fold a face or make a cap
    // that cannot be flipped; the run is not dropped for it: that vertex stays where it
    // is and the rest go onto the line, up to a third of the chain left off.
    std::vector<bool> stays(chain.size(), false);
    const int max_left = static_cast<int>(chain.size()) / 3;
    int left = 0;
    bool done = false;
    while (!done) {
      std::vector<std::pair<int, TinMesh::Point>> old;
      std::vector<double> moved_by;  // by chain position, 0 for vertices not moved
      double max_move = 0.0;
      for (size_t c = 0; c < chain.size(); ++c) {
        moved_by.push_back(0.0);
        if (stays[c]) continue;
        const int v = chain[c];
        const auto vh = mesh->vertex_handle(v);
        Eigen::Vector3d target = centre + along(v) * dir;
        if (mesh->is_boundary(vh)) {
          // A vertex on a straight stretch of the border slides along it to where the line
          // crosses it (the region's rim stays where it is).
          TinMesh::HalfedgeHandle out;
          for (auto heh : mesh->voh_range(vh)) {
            if (mesh->is_boundary(heh)) out = heh;
          }
          if (!out.is_valid()) continue;
          const Eigen::Vector3d next = ToEigen(mesh->point(mesh->to_vertex_handle(out)));
          const Eigen::Vector3d prev =
              ToEigen(mesh->point(mesh->from_vertex_handle(mesh->prev_halfedge_handle(out))));
          const Eigen::Vector3d p = point(v);
          // Straight in the tangent plane (the rim bends in height where it crosses a ridge).
          const Eigen::Vector3d n = ToEigen(mesh->normal(vh));
          Eigen::Vector3d e1 = p - prev, e2 = next - p;
          e1 -= e1.dot(n) * n;
          e2 -= e2.dot(n) * n;
          if (e1.normalized().dot(e2.normalized()) < 0.99) continue;
          const Eigen::Vector3d u = (e1.normalized() + e2.normalized()).normalized();
          const Eigen::Vector3d w0 = p - centre;
          const double b = u.dot(dir), d = u.dot(w0), e = dir.dot(w0);
          const double denom = 1.0 - b * b;
          if (denom < 0.1) continue;
          const double slide = (b * e - d) / denom, t = (e - b * d) / denom;
          const Eigen::Vector3d on_rim = p + slide * u, on_line = centre + t * dir;
          if (std::abs(slide) > 0.5 * h || (on_rim - on_line).norm() > 0.25 * h) continue;
          // Along the rim, and along the normal to the line's height: the rim's plane.
          target = on_rim + (on_line - on_rim).dot(n) * n;
        }
        old.emplace_back(v, mesh->point(vh));
        moved_by[c] = (target - point(v)).norm();
        max_move = std::max(max_move, moved_by[c]);
        mesh->set_point(vh, TinMesh::Point(target.x(), target.y(), target.z()));
      }
      // Where the chain zigzags through a face, all three of its corners are now on the
      // line: a cap with no area, whose normal is rounding noise (it passes the fold test
      // by chance) and whose G1 patch divides by its area (block, session 21: 36 crossing
      // facet pairs). Its long edge is flipped to the vertex across it, off the line: two
      // faces with area for one without, the chain's edges kept. A cap that cannot be
      // flipped (on the border, the vertex across on the line too, or a flipped face
      // turned) counts as a fold.
      TinMesh::FaceHandle failed;
      std::vector<TinMesh::EdgeHandle> cap_edges;
      for (size_t i = 0; i < faces.size() && !failed.is_valid(); ++i) {
        const auto fh = mesh->face_handle(faces[i]);
        std::array<TinMesh::HalfedgeHandle, 3> by_length;
        if (!DegenerateFace(*mesh, fh, kCapHeight, &by_length)) {
          if (UnitFaceNormal(*mesh, fh).dot(normal_before[i]) < 0.5) failed = fh;
          continue;
        }
        const auto longest = by_length[2];
        const double long_edge = mesh->calc_edge_length(longest);
        const auto edge = mesh->edge_handle(longest);
        if (mesh->is_boundary(edge) || !mesh->is_flip_ok(edge)) {
          failed = fh;
          continue;
        }
        // Face (a, b, apex) and across the long edge (b, a, other); flipped: (a, other,
        // apex) and (b, apex, other), each judged against both faces before the move.
        const auto across = mesh->opposite_halfedge_handle(longest);
        const Eigen::Vector3d a = ToEigen(mesh->point(mesh->from_vertex_handle(longest)));
        const Eigen::Vector3d b = ToEigen(mesh->point(mesh->to_vertex_handle(longest)));
        const Eigen::Vector3d apex =
            ToEigen(mesh->point(mesh->to_vertex_handle(mesh->next_halfedge_handle(longest))));
        const Eigen::Vector3d other =
            ToEigen(mesh->point(mesh->to_vertex_handle(mesh->next_halfedge_handle(across))));
        for (const Eigen::Vector3d& n : {Eigen::Vector3d((other - a).cross(apex - a)),
                                         Eigen::Vector3d((apex - b).cross(other - b))}) {
          if (NoArea(n.norm(), long_edge, kCapHeight)) {
            failed = fh;
            break;
          }
          for (auto face : {fh, mesh->face_handle(across)}) {
            if (n.normalized().dot(normal_before_of(face)) < 0.5) failed = fh;
          }
        }
        cap_edges.push_back(edge);
      }
      if (!failed.is_valid()) {
        for (auto edge : cap_edges) {
          mesh->flip(edge);
          for (int side : {0, 1}) {
            const auto fh = mesh->face_handle(mesh->halfedge_handle(edge, side));
            mesh->set_normal(fh, mesh->calc_face_normal(fh));
          }
        }
        report.flipped += static_cast<int>(cap_edges.size());
        report.moved += static_cast<int>(old.size());
        report.left_off += left;
        report.max_move = std::max(report.max_move, max_move);
        done = true;
        continue;
      }
      for (const auto& [v, p] : old) mesh->set_point(mesh->vertex_handle(v), p);
      // The failed face's corner that moved most stays where it was, and the run is tried again.
      int worst = -1;
      for (auto fv : mesh->fv_range(failed)) {
        const auto it = std::find(chain.begin(), chain.end(), fv.idx());
        if (it == chain.end()) continue;
        const size_t c = it - chain.begin();
        if (!stays[c] && moved_by[c] > 0.0 && (worst < 0 || moved_by[c] > moved_by[worst])) worst = static_cast<int>(c);
      }
      if (worst < 0 || left == max_left) {
        ++report.rejected;
        done = true;
        continue;
      }
      stays[worst] = true;
      ++left;
    }
  }
  if (report.moved > 0) UpdateVertexNormals(mesh);
  return report;
}

}  // namespace facets
