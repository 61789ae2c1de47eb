#include "mesh/local_ops.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <numbers>
#include <stdexcept>

#include "mesh/creases.h"

namespace facets {
namespace {

using Vec2 = Eigen::Vector2d;

// Orthonormal basis of the plane orthogonal to unit n.
void PlaneBasis(const Eigen::Vector3d& n, Eigen::Vector3d* e1, Eigen::Vector3d* e2) {
  const Eigen::Vector3d a =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  *e1 = (a - a.dot(n) * n).normalized();
  *e2 = n.cross(*e1);
}

double Cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

double Angle2(const Vec2& a, const Vec2& b) {
  return std::atan2(std::abs(Cross2(a, b)), a.dot(b));
}

// The quad of an interior edge projected into its tangent plane: a, b edge ends,
// c opposite in the face of halfedge 0, d opposite in the other face.
struct Quad {
  TinMesh::VertexHandle va, vb, vc, vd;
  Vec2 a, b, c, d;
};

bool EdgeQuad(const TinMesh& mesh, TinMesh::EdgeHandle eh, Quad* q) {
  if (mesh.is_boundary(eh)) return false;
  const auto h0 = mesh.halfedge_handle(eh, 0), h1 = mesh.halfedge_handle(eh, 1);
  q->va = mesh.from_vertex_handle(h0);
  q->vb = mesh.to_vertex_handle(h0);
  q->vc = mesh.to_vertex_handle(mesh.next_halfedge_handle(h0));
  q->vd = mesh.to_vertex_handle(mesh.next_halfedge_handle(h1));
  // Mean of all four vertex normals rather than only the edge's two: the plane is then
  // the same before and after a flip, so the criterion cannot flip an edge back and
  // forth (with the edge's two normals only, ab and its flip cd can both fail it).
  Eigen::Vector3d n = ToEigen(mesh.normal(q->va)) + ToEigen(mesh.normal(q->vb)) +
                      ToEigen(mesh.normal(q->vc)) + ToEigen(mesh.normal(q->vd));
  if (n.norm() < 1e-12) {
    n = ToEigen(mesh.calc_face_normal(mesh.face_handle(h0)) +
                mesh.calc_face_normal(mesh.face_handle(h1)));
  }
  n.normalize();
  Eigen::Vector3d e1, e2;
  PlaneBasis(n, &e1, &e2);
  const Eigen::Vector3d o = ToEigen(mesh.point(q->va));
  auto proj = [&](TinMesh::VertexHandle v) {
    const Eigen::Vector3d p = ToEigen(mesh.point(v)) - o;
    return Vec2(p.dot(e1), p.dot(e2));
  };
  q->a = proj(q->va);
  q->b = proj(q->vb);
  q->c = proj(q->vc);
  q->d = proj(q->vd);
  return true;
}

void UpdateFaceNormalsAround(TinMesh* mesh, TinMesh::VertexHandle v) {
  for (auto f : mesh->vf_range(v)) mesh->set_normal(f, mesh->calc_face_normal(f));
}

}  // namespace

TinMesh::VertexHandle SplitEdge(TinMesh* mesh, TinMesh::EdgeHandle eh) {
  const EdgeCurve curve = MakeEdgeCurve(*mesh, eh);
  const auto vh = mesh->add_vertex(ToOpenMesh(curve.Point(0.5)));
  mesh->set_normal(vh, ToOpenMesh(curve.Normal(0.5)));
  mesh->split_edge(eh, vh);
  UpdateFaceNormalsAround(mesh, vh);
  return vh;
}

bool IsTangentDelaunay(const TinMesh& mesh, TinMesh::EdgeHandle eh, double tolerance) {
  Quad q;
  if (!EdgeQuad(mesh, eh, &q)) return true;
  const double angle_c = Angle2(q.a - q.c, q.b - q.c);
  const double angle_d = Angle2(q.a - q.d, q.b - q.d);
  return angle_c + angle_d <= std::numbers::pi + tolerance;
}

bool CanFlip(const TinMesh& mesh, TinMesh::EdgeHandle eh) {
  Quad q;
  if (!EdgeQuad(mesh, eh, &q) || !mesh.is_flip_ok(eh)) return false;
  // Current faces (a, b, c) and (b, a, d) are counter-clockwise in the plane when not
  // folded; the flipped ones are (c, a, d) and (d, b, c).
  const double scale = (q.b - q.a).squaredNorm() + (q.c - q.d).squaredNorm();
  const double eps = 1e-12 * scale;
  return Cross2(q.a - q.c, q.d - q.c) > eps && Cross2(q.b - q.d, q.c - q.d) > eps;
}

namespace {

// Flips queued edges that are not Delaunay and CanFlip, queueing the edges of each
// flipped quad; with `within`, only edges with both ends flagged are flipped or queued.
int FlipQueued(TinMesh* mesh, const std::vector<bool>* within, int max_flips) {
  auto inside = [&](TinMesh::EdgeHandle e) {
    if (within == nullptr) return true;
    const auto h = mesh->halfedge_handle(e, 0);
    return (*within)[mesh->from_vertex_handle(h).idx()] && (*within)[mesh->to_vertex_handle(h).idx()];
  };
  std::deque<TinMesh::EdgeHandle> queue;
  std::vector<char> queued(mesh->n_edges(), 0);
  auto push = [&](TinMesh::EdgeHandle e) {
    if (queued[e.idx()] || !inside(e)) return;
    queued[e.idx()] = 1;
    queue.push_back(e);
  };
  for (auto e : mesh->edges()) push(e);
  int flips = 0;
  while (!queue.empty() && flips < max_flips) {
    const auto e = queue.front();
    queue.pop_front();
    queued[e.idx()] = 0;
    if (mesh->status(e).deleted() || IsTangentDelaunay(*mesh, e) || !CanFlip(*mesh, e)) {
      continue;
    }
    mesh->flip(e);
    ++flips;
    const auto h0 = mesh->halfedge_handle(e, 0), h1 = mesh->halfedge_handle(e, 1);
    mesh->set_normal(mesh->face_handle(h0), mesh->calc_face_normal(mesh->face_handle(h0)));
    mesh->set_normal(mesh->face_handle(h1), mesh->calc_face_normal(mesh->face_handle(h1)));
    for (auto h : {h0, h1}) {
      for (auto hh : {mesh->next_halfedge_handle(h), mesh->prev_halfedge_handle(h)}) push(mesh->edge_handle(hh));
    }
  }
  return flips;
}

}  // namespace

int MakeTangentDelaunay(TinMesh* mesh, int max_flips) {
  if (max_flips <= 0) max_flips = 10 * static_cast<int>(mesh->n_edges()) + 10;
  return FlipQueued(mesh, nullptr, max_flips);
}

int MakeTangentDelaunayWithin(TinMesh* mesh, const std::vector<bool>& within) {
  if (within.size() != mesh->n_vertices()) {
    throw std::invalid_argument("MakeTangentDelaunayWithin: one flag per vertex needed");
  }
  return FlipQueued(mesh, &within, 10 * static_cast<int>(mesh->n_edges()) + 10);
}

std::vector<bool> VerticesChangedFrom(const TinMesh& mesh, const TinMesh& before) {
  if (before.n_vertices() > mesh.n_vertices() || before.n_faces() > mesh.n_faces()) {
    throw std::invalid_argument("VerticesChangedFrom: the surface before has more vertices or faces");
  }
  std::vector<bool> changed(mesh.n_vertices(), true);
  for (auto v : before.vertices()) changed[v.idx()] = mesh.point(mesh.vertex_handle(v.idx())) != before.point(v);
  for (auto f : mesh.faces()) {
    bool same = static_cast<size_t>(f.idx()) < before.n_faces();
    if (same) {
      std::array<int, 3> now{}, was{};
      int k = 0;
      for (auto v : mesh.fv_range(f)) now[k++] = v.idx();
      k = 0;
      for (auto v : before.fv_range(before.face_handle(f.idx()))) was[k++] = v.idx();
      same = now == was;
    }
    if (same) continue;
    for (auto v : mesh.fv_range(f)) changed[v.idx()] = true;
  }
  return changed;
}

bool RemoveVertex(TinMesh* mesh, TinMesh::VertexHandle vh) {
  TinMesh::HalfedgeHandle best;
  double best_len = 0.0;
  for (auto h : mesh->voh_range(vh)) {
    if (!mesh->is_collapse_ok(h)) continue;
    // On the boundary only collapse along the boundary, so the rim keeps its shape.
    if (mesh->is_boundary(vh) && !mesh->is_boundary(mesh->edge_handle(h))) continue;
    const double len = mesh->calc_edge_length(h);
    if (!best.is_valid() || len < best_len) {
      best = h;
      best_len = len;
    }
  }
  if (!best.is_valid()) return false;
  const auto keep = mesh->to_vertex_handle(best);
  mesh->collapse(best);
  UpdateFaceNormalsAround(mesh, keep);
  // Restore Delaunay in the neighbourhood: flip edges of the kept vertex's star.
  bool flipped = true;
  for (int round = 0; flipped && round < 20; ++round) {
    flipped = false;
    std::vector<TinMesh::EdgeHandle> edges;
    for (auto f : mesh->vf_range(keep)) {
      for (auto e : mesh->fe_range(f)) edges.push_back(e);
    }
    for (auto e : edges) {
      if (!mesh->status(e).deleted() && !IsTangentDelaunay(*mesh, e) && CanFlip(*mesh, e)) {
        mesh->flip(e);
        for (int s = 0; s < 2; ++s) {
          const auto f = mesh->face_handle(mesh->halfedge_handle(e, s));
          mesh->set_normal(f, mesh->calc_face_normal(f));
        }
        flipped = true;
      }
    }
  }
  mesh->garbage_collection();
  return true;
}

bool NoArea(double twice_area, double longest, double relative_height) {
  return !(twice_area / longest >= relative_height * longest);
}

bool DegenerateFace(const TinMesh& mesh, TinMesh::FaceHandle f, double relative_height,
                    std::array<TinMesh::HalfedgeHandle, 3>* by_length) {
  int k = 0;
  for (auto h : mesh.fh_range(f)) (*by_length)[k++] = h;
  std::sort(by_length->begin(), by_length->end(), [&](auto a, auto b) {
    return mesh.calc_edge_length(a) < mesh.calc_edge_length(b);
  });
  const double longest = mesh.calc_edge_length((*by_length)[2]);
  const double twice_area = (mesh.calc_edge_vector((*by_length)[0]) % mesh.calc_edge_vector((*by_length)[1])).norm();
  return NoArea(twice_area, longest, relative_height);
}

int CountDegenerate(const TinMesh& mesh, double relative_height) {
  std::array<TinMesh::HalfedgeHandle, 3> by_length;
  int count = 0;
  for (auto f : mesh.faces()) count += DegenerateFace(mesh, f, relative_height, &by_length);
  return count;
}

namespace {

// Collapses `h` or its opposite (whichever OpenMesh allows; a boundary vertex is not
// pulled off the boundary along an inner edge).
bool CollapseEither(TinMesh* mesh, TinMesh::HalfedgeHandle h) {
  for (auto c : {h, mesh->opposite_halfedge_handle(h)}) {
    const bool from_boundary = mesh->is_boundary(mesh->from_vertex_handle(c));
    if (from_boundary && !mesh->is_boundary(mesh->edge_handle(c))) continue;
    if (!mesh->is_collapse_ok(c)) continue;
    mesh->collapse(c);
    return true;
  }
  return false;
}

}  // namespace

DegenerateRepairReport RepairDegenerateTriangles(TinMesh* mesh, double relative_height) {
  DegenerateRepairReport report;
  report.degenerate = CountDegenerate(*mesh, relative_height);
  report.left = report.degenerate;
  if (report.degenerate == 0) return report;
  for (int round = 0; round < 10 && report.left > 0; ++round) {
    bool changed = false;
    std::vector<TinMesh::FaceHandle> faces(mesh->faces_begin(), mesh->faces_end());
    std::array<TinMesh::HalfedgeHandle, 3> by_length;
    for (auto f : faces) {
      if (mesh->status(f).deleted() || !DegenerateFace(*mesh, f, relative_height, &by_length)) continue;
      const double longest = mesh->calc_edge_length(by_length[2]);
      if (mesh->calc_edge_length(by_length[0]) < relative_height * longest) {
        if (CollapseEither(mesh, by_length[0])) {
          ++report.collapsed;
          changed = true;
        }
        continue;
      }
      // A cap: the vertex opposite the longest edge lies on it. Flip that edge when the
      // vertex across it is off the line (else the flip makes another cap).
      const auto e = mesh->edge_handle(by_length[2]);
      const auto apex = mesh->to_vertex_handle(mesh->next_halfedge_handle(by_length[2]));
      const auto a = mesh->from_vertex_handle(by_length[2]), b = mesh->to_vertex_handle(by_length[2]);
      if (!mesh->is_boundary(e) && mesh->is_flip_ok(e)) {
        const auto across = mesh->opposite_halfedge_handle(by_length[2]);
        const auto other = mesh->to_vertex_handle(mesh->next_halfedge_handle(across));
        const double twice_area = ((mesh->point(b) - mesh->point(a)) % (mesh->point(other) - mesh->point(a))).norm();
        if (!NoArea(twice_area, longest, relative_height)) {
          mesh->flip(e);
          ++report.flipped;
          changed = true;
          continue;
        }
      }
      // Otherwise (the boundary, or a flat fan) the cap vertex goes into the nearer end of
      // the long edge, or the farther one.
      const bool a_nearer = (mesh->point(apex) - mesh->point(a)).norm() <= (mesh->point(apex) - mesh->point(b)).norm();
      for (auto end : {a_nearer ? a : b, a_nearer ? b : a}) {
        const auto h = mesh->find_halfedge(apex, end);
        if (h.is_valid() && CollapseEither(mesh, h)) {
          ++report.collapsed;
          changed = true;
          break;
        }
      }
    }
    if (!changed) break;
    mesh->garbage_collection();
    report.left = CountDegenerate(*mesh, relative_height);
  }
  mesh->update_face_normals();
  UpdateVertexNormals(mesh);
  return report;
}

void SmoothingOptions::Check() const {
  if (iterations < 0) throw std::invalid_argument("SmoothingOptions: iterations < 0");
  if (!(step > 0.0 && step <= 0.5)) {
    throw std::invalid_argument("SmoothingOptions: step must be in (0, 0.5]");
  }
  if (!(crease_angle_deg > 0.0)) throw std::invalid_argument("SmoothingOptions: crease_angle_deg must be > 0");
}

namespace {

// The point of the G1 surface (patches, by face) over p + delta: located in the face
// around v whose projection onto the tangent plane at p (normal n) contains it, with
// the surface's normal there. False (nothing set) when no such face.
bool OntoAdjacentPatch(const TinMesh& mesh, const std::vector<G1Patch>& patches, TinMesh::VertexHandle v,
                       const Eigen::Vector3d& p, const Eigen::Vector3d& n, const Eigen::Vector3d& delta,
                       Eigen::Vector3d* moved, Eigen::Vector3d* moved_normal) {
  Eigen::Vector3d e1, e2;
  PlaneBasis(n, &e1, &e2);
  for (auto f : mesh.vf_range(v)) {
    const G1Patch& patch = patches[f.idx()];
    Vec2 x[3];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d r = patch.vertex(k) - p;
      x[k] = Vec2(r.dot(e1), r.dot(e2));
    }
    const Vec2 t(delta.dot(e1), delta.dot(e2));
    const double area = Cross2(x[1] - x[0], x[2] - x[0]);
    if (std::abs(area) < 1e-300) continue;
    const double b1 = Cross2(t - x[0], x[2] - x[0]) / area;
    const double b2 = Cross2(x[1] - x[0], t - x[0]) / area;
    const double b0 = 1.0 - b1 - b2;
    const double eps = -1e-12;
    if (b0 >= eps && b1 >= eps && b2 >= eps) {
      const SurfacePoint sp = patch.EvaluateWithDerivatives(b1, b2);
      *moved = sp.point;
      *moved_normal = sp.normal;
      return true;
    }
  }
  return false;
}

}  // namespace

SmoothingReport TangentialSmooth(TinMesh* mesh, const SmoothingOptions& options) {
  options.Check();
  SmoothingReport report;
  const size_t nv = mesh->n_vertices();
  std::vector<Eigen::Vector3d> new_point(nv), new_normal(nv);
  for (int it = 0; it < options.iterations; ++it) {
    std::vector<G1Patch> patches;
    std::vector<int> sectors;
    if (options.crease_angle_deg < 180.0) {
      CornerNormals corners =
          ComputeCornerNormals(*mesh, options.crease_angle_deg, options.rounded_ridges);
      patches = BuildPatches(*mesh, corners);
      sectors = std::move(corners.vertex_sectors);
      report.crease_vertices = corners.num_crease_vertices;
    } else {
      patches = BuildPatches(*mesh);
    }
    for (auto v : mesh->vertices()) {
      const Eigen::Vector3d p = ToEigen(mesh->point(v));
      const Eigen::Vector3d n = ToEigen(mesh->normal(v));
      new_point[v.idx()] = p;
      new_normal[v.idx()] = n;
      if ((options.fix_boundary && mesh->is_boundary(v)) || mesh->valence(v) == 0) continue;
      if (!sectors.empty() && sectors[v.idx()] > 1) continue;  // on a crease
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      int count = 0;
      for (auto w : mesh->vv_range(v)) {
        centroid += ToEigen(mesh->point(w));
        ++count;
      }
      centroid /= count;
      Eigen::Vector3d delta = options.step * (centroid - p);
      delta -= delta.dot(n) * n;
      const Eigen::Vector3d target = p + delta;
      Eigen::Vector3d moved = target, moved_normal = n;
      if (options.stay_on_surface && !OntoAdjacentPatch(*mesh, patches, v, p, n, delta, &moved, &moved_normal)) {
        ++report.off_surface;
      }
      if (!moved.allFinite() || !(moved_normal.norm() > 0.5)) {
        // A degenerate patch (a folded vertex: tangents parallel, no normal): stay.
        moved = p;
        moved_normal = n;
      }
      new_point[v.idx()] = moved;
      new_normal[v.idx()] = moved_normal;
      const double move = (moved - p).norm();
      if (move > 0.0) ++report.moved;
      report.max_move = std::max(report.max_move, move);
    }
    for (auto v : mesh->vertices()) {
      mesh->set_point(v, ToOpenMesh(new_point[v.idx()]));
      mesh->set_normal(v, ToOpenMesh(new_normal[v.idx()]));
    }
    for (auto f : mesh->faces()) mesh->set_normal(f, mesh->calc_face_normal(f));
  }
  return report;
}

void QualityOptions::Check() const {
  if (!(target_edge_length > 0.0) || !std::isfinite(target_edge_length)) {
    throw std::invalid_argument("QualityOptions: target_edge_length must be positive");
  }
  if (!(split_factor > 1.0)) throw std::invalid_argument("QualityOptions: split_factor <= 1");
  if (max_rounds < 0) throw std::invalid_argument("QualityOptions: max_rounds < 0");
}

QualityReport QualityPass(TinMesh* mesh, const QualityOptions& options) {
  options.Check();
  QualityReport report;
  const double limit = options.split_factor * options.target_edge_length;
  if (options.near != nullptr && options.near->size() != mesh->n_vertices()) {
    throw std::invalid_argument("QualityPass: one `near` flag per vertex needed");
  }
  // A vertex inserted on an edge between two flagged ones is flagged too; one on an edge
  // leaving the flagged vertices is not, so the splits do not creep outwards round by round.
  std::vector<bool> flagged = options.near != nullptr ? *options.near : std::vector<bool>();
  auto near = [&](TinMesh::VertexHandle v) { return options.near == nullptr || flagged[v.idx()]; };
  for (int round = 0; round < options.max_rounds; ++round) {
    std::vector<std::pair<double, TinMesh::EdgeHandle>> long_edges;
    for (auto e : mesh->edges()) {
      const double len = mesh->calc_edge_length(e);
      const auto h = mesh->halfedge_handle(e, 0);
      if (len > limit && (near(mesh->from_vertex_handle(h)) || near(mesh->to_vertex_handle(h)))) {
        long_edges.emplace_back(len, e);
      }
    }
    if (long_edges.empty()) break;
    // Longest first; edges created by earlier splits in this round wait for the next.
    std::sort(long_edges.begin(), long_edges.end(),
              [](const auto& x, const auto& y) { return x.first > y.first; });
    for (const auto& [len, e] : long_edges) {
      if (mesh->calc_edge_length(e) <= limit) continue;
      const auto h = mesh->halfedge_handle(e, 0);
      const bool both_near = near(mesh->from_vertex_handle(h)) && near(mesh->to_vertex_handle(h));
      SplitEdge(mesh, e);
      if (options.near != nullptr) flagged.push_back(both_near);
      ++report.splits;
    }
  }
  if (options.near == nullptr) {
    report.flips = MakeTangentDelaunay(mesh);
  } else {
    std::vector<bool> within = *options.near;  // and every inserted vertex
    within.resize(mesh->n_vertices(), true);
    report.flips = MakeTangentDelaunayWithin(mesh, within);
  }
  for (auto e : mesh->edges()) {
    report.max_edge_length = std::max(report.max_edge_length, mesh->calc_edge_length(e));
  }
  return report;
}

int CountLongEdges(const TinMesh& mesh, const QualityOptions& options) {
  options.Check();
  const double limit = options.split_factor * options.target_edge_length;
  auto near = [&](TinMesh::VertexHandle v) { return options.near == nullptr || (*options.near)[v.idx()]; };
  int count = 0;
  for (auto e : mesh.edges()) {
    const auto h = mesh.halfedge_handle(e, 0);
    const bool counted = near(mesh.from_vertex_handle(h)) || near(mesh.to_vertex_handle(h));
    count += counted && mesh.calc_edge_length(e) > limit ? 1 : 0;
  }
  return count;
}

int RelaxUnseenVertices(TinMesh* mesh, const std::vector<int>& views, int iterations) {
  if (views.size() != mesh->n_vertices()) {
    throw std::invalid_argument("RelaxUnseenVertices: one view count per vertex needed");
  }
  std::vector<int> free;
  for (auto v : mesh->vertices()) {
    if (views[v.idx()] == 0 && !mesh->is_boundary(v) && mesh->valence(v) > 0) free.push_back(v.idx());
  }
  std::vector<Eigen::Vector3d> next(free.size());
  for (int it = 0; it < iterations && !free.empty(); ++it) {
    for (size_t i = 0; i < free.size(); ++i) {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      int count = 0;
      for (auto w : mesh->vv_range(mesh->vertex_handle(free[i]))) {
        mean += ToEigen(mesh->point(w));
        ++count;
      }
      next[i] = mean / count;
    }
    for (size_t i = 0; i < free.size(); ++i) mesh->set_point(mesh->vertex_handle(free[i]), ToOpenMesh(next[i]));
  }
  return static_cast<int>(free.size());
}

AngleStats FaceAngleStats(const TinMesh& mesh) {
  AngleStats stats;
  stats.min_angle = std::numbers::pi;
  double sum = 0.0;
  for (auto f : mesh.faces()) {
    Eigen::Vector3d x[3];
    int k = 0;
    for (auto v : mesh.fv_range(f)) x[k++] = ToEigen(mesh.point(v));
    double m = std::numbers::pi;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d a = x[(i + 1) % 3] - x[i], b = x[(i + 2) % 3] - x[i];
      m = std::min(m, std::atan2(a.cross(b).norm(), a.dot(b)));
    }
    stats.min_angle = std::min(stats.min_angle, m);
    sum += m;
  }
  stats.mean_min_angle = mesh.n_faces() ? sum / mesh.n_faces() : 0.0;
  return stats;
}

}  // namespace facets
