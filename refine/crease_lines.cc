#include "refine/crease_lines.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <utility>

#include "mesh/creases.h"
#include "mesh/local_ops.h"
#include "mesh/principal_axes.h"

namespace facets {
namespace {

// A face is a cap (no area: its corners on one line) when its height over its longest
// edge is below this fraction of that edge (NoArea, mesh/local_ops.h).
constexpr double kCapHeight = 1e-3;
// The two side planes of a crease line must meet at least at this angle (degrees).
constexpr double kCreaseMinDeg = 10.0;
// The side planes are fitted 1-3 edges from the run's line (in edge lengths): nearer
// than one edge the regularisation still rounds the crease.
constexpr double kSideNear = 1.0, kSideFar = 3.0;

int FindRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

Eigen::Vector3d VertexPoint(const TinMesh& mesh, int v) { return ToEigen(mesh.point(mesh.vertex_handle(v))); }

// A line through centre along the unit vector dir; positions along it and distances
// from it in m.
struct Line {
  Eigen::Vector3d centre, dir;
  double Along(const Eigen::Vector3d& p) const { return (p - centre).dot(dir); }
  double Off(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - centre;
    return (d - d.dot(dir) * dir).norm();
  }
};

// The longest stretch of on_line (sorted by position along the line) without a gap of
// more than 1.5 edges, when it holds more vertices than *best (then also its span in m).
void TakeLongestStretch(const std::vector<std::pair<double, int>>& on_line, double h, std::vector<int>* best,
                        double* best_span) {
  size_t begin = 0;
  for (size_t i = 1; i <= on_line.size(); ++i) {
    if (i < on_line.size() && on_line[i].first - on_line[i - 1].first <= 1.5 * h) continue;
    if (i - begin > best->size()) {
      best->clear();
      for (size_t k = begin; k < i; ++k) best->push_back(on_line[k].second);
      *best_span = on_line[i - 1].first - on_line[begin].first;
    }
    begin = i;
  }
}

// Straight runs of a set of crease vertices: lines through two of its vertices (drawn
// at random with a fixed seed, so runs are reproducible), the one with the most
// vertices within max_offset edges in one stretch without a gap of more than 1.5
// edges; its vertices leave the set and the next line is sought, until no stretch
// spans min_edges edges. A straight set gives one run.
std::vector<std::vector<int>> StraightRuns(const TinMesh& mesh, std::vector<int> remaining, double h,
                                           double max_offset, int min_edges) {
  std::vector<std::vector<int>> runs;
  std::mt19937 random(12345);
  auto point = [&](int v) { return VertexPoint(mesh, v); };
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
      TakeLongestStretch(on_line, h, &best, &best_span);
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

// A straight run of crease vertices, a candidate line.
struct Candidate {
  std::vector<int> vertices;
  double h;        // m, the mean length of its set's crease edges
  bool whole_set;  // the set is one straight run
};

// Connected sets of crease vertices, each with the total length and count of its crease
// edges (indexed by the set's root vertex).
struct CreaseSets {
  std::vector<std::vector<int>> members;
  std::vector<double> edge_sum;
  std::vector<int> edge_count;
};

CreaseSets FindCreaseSets(const TinMesh& mesh, const std::vector<bool>& crease_edge) {
  const int nv = static_cast<int>(mesh.n_vertices());
  std::vector<int> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<bool> on_crease(nv, false);
  for (auto eh : mesh.edges()) {
    if (!crease_edge[eh.idx()]) continue;
    const int a = mesh.to_vertex_handle(mesh.halfedge_handle(eh, 0)).idx();
    const int b = mesh.from_vertex_handle(mesh.halfedge_handle(eh, 0)).idx();
    on_crease[a] = on_crease[b] = true;
    parent[FindRoot(parent, a)] = FindRoot(parent, b);
  }
  // A zigzag's step edges bend less than its runs and may miss the crease angle: crease
  // vertices joined by any edge belong to one set.
  for (auto eh : mesh.edges()) {
    const int a = mesh.to_vertex_handle(mesh.halfedge_handle(eh, 0)).idx();
    const int b = mesh.from_vertex_handle(mesh.halfedge_handle(eh, 0)).idx();
    if (on_crease[a] && on_crease[b]) parent[FindRoot(parent, a)] = FindRoot(parent, b);
  }
  CreaseSets sets;
  sets.members.resize(nv);
  for (int v = 0; v < nv; ++v) {
    if (on_crease[v]) sets.members[FindRoot(parent, v)].push_back(v);
  }
  sets.edge_sum.assign(nv, 0.0);
  sets.edge_count.assign(nv, 0);
  for (auto eh : mesh.edges()) {
    if (!crease_edge[eh.idx()]) continue;
    const int root = FindRoot(parent, mesh.to_vertex_handle(mesh.halfedge_handle(eh, 0)).idx());
    sets.edge_sum[root] += mesh.calc_edge_length(eh);
    ++sets.edge_count[root];
  }
  return sets;
}

// A building's creases form one web (eaves, ridges, wall corners joined at their
// ends): it is cut into straight runs first, and each run is a candidate line.
std::vector<Candidate> CandidateRuns(const TinMesh& mesh, const std::vector<bool>& crease_edge, int min_edges,
                                     double max_offset, StraightenReport* report) {
  CreaseSets sets = FindCreaseSets(mesh, crease_edge);
  std::vector<Candidate> candidates;
  for (size_t root = 0; root < sets.members.size(); ++root) {
    if (sets.members[root].empty()) continue;
    ++report->sets;
    if (sets.edge_count[root] < min_edges) {
      ++report->too_small;
      continue;
    }
    const double h = sets.edge_sum[root] / sets.edge_count[root];
    std::vector<std::vector<int>> runs = StraightRuns(mesh, sets.members[root], h, max_offset, min_edges);
    const bool whole = runs.size() == 1 && runs[0].size() == sets.members[root].size();
    for (std::vector<int>& run : runs) candidates.push_back({std::move(run), h, whole});
  }
  report->lines = static_cast<int>(candidates.size());
  return candidates;
}

// Least-squares line of the run's vertices; vertices farther than max_offset edges are
// dropped and the line refitted. False when fewer than 3 vertices stay.
bool FitRunLine(const TinMesh& mesh, double h, double max_offset, std::vector<int>* kept, Line* line) {
  for (int round = 0; round < 3; ++round) {
    if (kept->size() < 3) break;
    std::vector<Eigen::Vector3d> points;
    for (int v : *kept) points.push_back(VertexPoint(mesh, v));
    const PrincipalAxes fit = FitPrincipalAxes(points);
    line->centre = fit.centre;
    line->dir = fit.Direction();
    std::vector<int> next;
    for (int v : *kept) {
      const Eigen::Vector3d d = VertexPoint(mesh, v) - line->centre;
      if ((d - d.dot(line->dir) * line->dir).norm() <= max_offset * h) next.push_back(v);
    }
    if (next.size() == kept->size()) break;
    *kept = std::move(next);
  }
  return kept->size() >= 3;
}

// The plane of one side's points when it is planar: rms distance to the plane within a
// tenth of an edge, after points off it (another roof face past a hip line's end, a
// wall below an eave) are dropped, as long as three quarters of them stay.
bool FitPlanarSide(const std::vector<Eigen::Vector3d>& side_points, double h, Eigen::Vector3d* normal,
                   Eigen::Vector3d* centre) {
  std::vector<Eigen::Vector3d> on_plane = side_points;
  double rms = 0.0;
  for (int round = 0; round < 3; ++round) {
    const PrincipalAxes fit = FitPrincipalAxes(on_plane);
    *centre = fit.centre;
    *normal = fit.Normal();
    rms = std::sqrt(std::max(0.0, fit.eigenvalues(0)) / on_plane.size());
    if (rms <= 0.1 * h) break;
    std::vector<Eigen::Vector3d> closer;
    for (const auto& q : on_plane) {
      if (std::abs((q - *centre).dot(*normal)) <= std::max(2.0 * rms, 0.1 * h)) closer.push_back(q);
    }
    if (closer.size() < 4 || closer.size() == on_plane.size() || 4 * closer.size() < 3 * side_points.size()) break;
    on_plane = std::move(closer);
  }
  return rms <= 0.1 * h;
}

// The planes of the surface on either side of a run, relative to the run line's centre.
struct SidePlanes {
  Eigen::Vector3d normal[2], centre[2];
};

// The vertices of a zigzag lie mostly on one side of the true crease, so their line
// is off by up to half an edge: the line is the intersection of the planes fitted to
// the surface on either side (1-3 edges away). False when a side is not planar.
bool FitSidePlanes(const TinMesh& mesh, const std::vector<int>& kept, const Line& line, double h, double t_min,
                   double t_max, bool whole_set, SidePlanes* planes) {
  Eigen::Vector3d mean_normal = Eigen::Vector3d::Zero();
  for (int v : kept) mean_normal += ToEigen(mesh.normal(mesh.vertex_handle(v)));
  const Eigen::Vector3d side_axis = mean_normal.cross(line.dir).normalized();
  std::vector<Eigen::Vector3d> side_points[2];
  // Along the whole line; for a run cut from a web not within an edge of its ends,
  // where the other creases of the web and their faces begin.
  const double side_from = whole_set ? t_min - 0.5 * h : t_min + h;
  const double side_to = whole_set ? t_max + 0.5 * h : t_max - h;
  for (auto vh : mesh.vertices()) {
    const Eigen::Vector3d d = ToEigen(mesh.point(vh)) - line.centre;
    const double t = d.dot(line.dir), s = d.dot(side_axis);
    if (t < side_from || t > side_to || std::abs(s) < kSideNear * h || std::abs(s) > kSideFar * h) continue;
    // Near the crease only: the slab of side distances also holds surface far along
    // the normal (the ground under an eave, the roof above a wall's foot).
    if ((d - t * line.dir).norm() > 1.5 * kSideFar * h) continue;
    side_points[s > 0.0 ? 1 : 0].push_back(d);
  }
  bool planar = side_points[0].size() >= 4 && side_points[1].size() >= 4;
  for (int k = 0; k < 2 && planar; ++k) {
    planar = FitPlanarSide(side_points[k], h, &planes->normal[k], &planes->centre[k]);
  }
  return planar;
}

// Moves *line onto the line where the side planes meet, when they meet at
// kCreaseMinDeg or more, within 20 degrees of the line and within an edge of its centre.
bool LineWherePlanesMeet(const SidePlanes& planes, double h, Line* line) {
  Eigen::Vector3d line_dir = planes.normal[0].cross(planes.normal[1]);
  if (line_dir.norm() < std::sin(kCreaseMinDeg * M_PI / 180.0)) return false;
  line_dir.normalize();
  if (line_dir.dot(line->dir) < 0.0) line_dir = -line_dir;
  if (line_dir.dot(line->dir) < std::cos(20.0 * M_PI / 180.0)) return false;
  // The point of the line nearest the old centre: both plane equations plus t = 0.
  Eigen::Matrix3d a;
  a.row(0) = planes.normal[0].transpose();
  a.row(1) = planes.normal[1].transpose();
  a.row(2) = line_dir.transpose();
  const Eigen::Vector3d rhs(planes.normal[0].dot(planes.centre[0]), planes.normal[1].dot(planes.centre[1]), 0.0);
  const Eigen::Vector3d line_point = a.colPivHouseholderQr().solve(rhs);
  if (line_point.norm() > h) return false;
  line->centre += line_point;
  line->dir = line_dir;
  return true;
}

// The chain of vertices along the line from `middle` in direction sense (+1 or -1) up
// to position limit along the line: each step to the neighbour that advances by at
// least a third of an edge and lies closest to the line, within max_offset edges.
std::vector<int> FollowHalfChain(const TinMesh& mesh, const Line& line, int middle, int sense, double limit, double h,
                                 double max_offset) {
  auto along = [&](int v) { return line.Along(VertexPoint(mesh, v)); };
  auto off = [&](int v) { return line.Off(VertexPoint(mesh, v)); };
  std::vector<int> half{middle};
  while (true) {
    const double t = along(half.back());
    int best = -1;
    // A step across the line's direction (a grid edge nearly perpendicular to it)
    // only when no neighbour advances by a third of an edge.
    for (double advance : {h / 3.0, 0.1 * h}) {
      for (auto w : mesh.vv_range(mesh.vertex_handle(half.back()))) {
        const double tw = along(w.idx());
        if (sense * (tw - t) < advance || sense * (tw - limit) > 0.0 || off(w.idx()) > max_offset * h) continue;
        if (best < 0 || off(w.idx()) < off(best)) best = w.idx();
      }
      if (best >= 0) break;
    }
    if (best < 0) break;
    half.push_back(best);
  }
  return half;
}

// From the vertex nearest the line in the middle of the run, through the mesh to both
// ends, one and a half edges beyond the run's crease vertices (the crease may fade out
// before the ridge ends). Empty when no vertex lies near the line in the middle.
std::vector<int> FollowChain(const TinMesh& mesh, const std::vector<int>& kept, const Line& line, double h,
                             double max_offset, bool whole_set) {
  auto along = [&](int v) { return line.Along(VertexPoint(mesh, v)); };
  auto off = [&](int v) { return line.Off(VertexPoint(mesh, v)); };
  double t_end = -std::numeric_limits<double>::infinity();
  double t_start = std::numeric_limits<double>::infinity();
  for (int v : kept) {
    t_start = std::min(t_start, along(v));
    t_end = std::max(t_end, along(v));
  }
  const double t_mid = 0.5 * (t_start + t_end);
  int middle = -1;
  for (auto vh : mesh.vertices()) {
    const double t = along(vh.idx());
    if (std::abs(t - t_mid) > 0.5 * h || off(vh.idx()) > max_offset * h) continue;
    if (middle < 0 || off(vh.idx()) < off(middle)) middle = vh.idx();
  }
  if (middle < 0) return {};
  std::vector<int> chain;
  for (int sense : {-1, 1}) {
    // A run cut from a web ends where other creases begin: its chain stops half an
    // edge short of the junction, whose vertices the runs would pull apart.
    const double beyond = whole_set ? 1.5 * h : -0.5 * h;
    const double limit = sense > 0 ? t_end + beyond : t_start - beyond;
    const std::vector<int> half = FollowHalfChain(mesh, line, middle, sense, limit, h, max_offset);
    if (sense < 0) {
      chain.assign(half.rbegin(), half.rend());
    } else {
      chain.insert(chain.end(), half.begin() + 1, half.end());
    }
  }
  return chain;
}

// Where a vertex on a straight stretch of the border goes: it slides along the border
// to where the line crosses it (the region's rim stays where it is). False when the
// border bends there or does not come near the line.
bool BorderTarget(const TinMesh& mesh, TinMesh::VertexHandle vh, const Line& line, double h,
                  Eigen::Vector3d* target) {
  TinMesh::HalfedgeHandle out;
  for (auto heh : mesh.voh_range(vh)) {
    if (mesh.is_boundary(heh)) out = heh;
  }
  if (!out.is_valid()) return false;
  const Eigen::Vector3d next = ToEigen(mesh.point(mesh.to_vertex_handle(out)));
  const Eigen::Vector3d prev = ToEigen(mesh.point(mesh.from_vertex_handle(mesh.prev_halfedge_handle(out))));
  const Eigen::Vector3d p = VertexPoint(mesh, vh.idx());
  // Straight in the tangent plane (the rim bends in height where it crosses a ridge).
  const Eigen::Vector3d n = ToEigen(mesh.normal(vh));
  Eigen::Vector3d e1 = p - prev, e2 = next - p;
  e1 -= e1.dot(n) * n;
  e2 -= e2.dot(n) * n;
  if (e1.normalized().dot(e2.normalized()) < 0.99) return false;
  const Eigen::Vector3d u = (e1.normalized() + e2.normalized()).normalized();
  const Eigen::Vector3d w0 = p - line.centre;
  const double b = u.dot(line.dir), d = u.dot(w0), e = line.dir.dot(w0);
  const double denom = 1.0 - b * b;
  if (denom < 0.1) return false;
  const double slide = (b * e - d) / denom, t = (e - b * d) / denom;
  const Eigen::Vector3d on_rim = p + slide * u, on_line = line.centre + t * line.dir;
  if (std::abs(slide) > 0.5 * h || (on_rim - on_line).norm() > 0.25 * h) return false;
  // Along the rim, and along the normal to the line's height: the rim's plane.
  *target = on_rim + (on_line - on_rim).dot(n) * n;
  return true;
}

// One try at putting a chain onto its line: the positions before, and how far each
// chain position moved (m, 0 for vertices that stay or were not moved).
struct ChainMove {
  std::vector<std::pair<int, TinMesh::Point>> old;
  std::vector<double> moved_by;
  double max_move = 0.0;
};

ChainMove MoveChainOntoLine(TinMesh* mesh, const std::vector<int>& chain, const std::vector<bool>& stays,
                            const Line& line, double h) {
  ChainMove move;
  for (size_t c = 0; c < chain.size(); ++c) {
    move.moved_by.push_back(0.0);
    if (stays[c]) continue;
    const int v = chain[c];
    const auto vh = mesh->vertex_handle(v);
    Eigen::Vector3d target = line.centre + line.Along(VertexPoint(*mesh, v)) * line.dir;
    if (mesh->is_boundary(vh) && !BorderTarget(*mesh, vh, line, h, &target)) continue;
    move.old.emplace_back(v, mesh->point(vh));
    move.moved_by[c] = (target - VertexPoint(*mesh, v)).norm();
    move.max_move = std::max(move.max_move, move.moved_by[c]);
    mesh->set_point(vh, TinMesh::Point(target.x(), target.y(), target.z()));
  }
  return move;
}

// The faces around a chain (sorted indices) with their unit normals before it moved.
struct FacesBefore {
  std::vector<int> faces;
  std::vector<Eigen::Vector3d> normal;
  Eigen::Vector3d NormalOf(TinMesh::FaceHandle fh) const {
    const auto it = std::lower_bound(faces.begin(), faces.end(), fh.idx());
    return it != faces.end() && *it == fh.idx() ? normal[it - faces.begin()] : Eigen::Vector3d::Zero().eval();
  }
};

// Whether the cap fh (no area), flipped across its longest edge, gives two faces with
// area, each within 60 degrees of both faces before the move.
bool CapFlipsWell(const TinMesh& mesh, TinMesh::FaceHandle fh, TinMesh::HalfedgeHandle longest,
                  const FacesBefore& before) {
  const double long_edge = mesh.calc_edge_length(longest);
  // Face (a, b, apex) and across the long edge (b, a, other); flipped: (a, other,
  // apex) and (b, apex, other), each judged against both faces before the move.
  const auto across = mesh.opposite_halfedge_handle(longest);
  const Eigen::Vector3d a = ToEigen(mesh.point(mesh.from_vertex_handle(longest)));
  const Eigen::Vector3d b = ToEigen(mesh.point(mesh.to_vertex_handle(longest)));
  const Eigen::Vector3d apex = ToEigen(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(longest))));
  const Eigen::Vector3d other = ToEigen(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(across))));
  bool good = true;
  for (const Eigen::Vector3d& n :
       {Eigen::Vector3d((other - a).cross(apex - a)), Eigen::Vector3d((apex - b).cross(other - b))}) {
    if (NoArea(n.norm(), long_edge, kCapHeight)) return false;
    for (auto face : {fh, mesh.face_handle(across)}) {
      if (n.normalized().dot(before.NormalOf(face)) < 0.5) good = false;
    }
  }
  return good;
}

// Where the chain zigzags through a face, all three of its corners are now on the
// line: a cap with no area, whose normal is rounding noise (it passes the fold test
// by chance) and whose G1 patch divides by its area (crossing facets in the output).
// Its long edge is to be flipped to the vertex across it, off the line: two faces with
// area for one without, the chain's edges kept. Returns the first face that folds
// (turns by more than 60 degrees) or is a cap that cannot be flipped (on the border,
// the vertex across on the line too, or a flipped face turned); invalid when none,
// with the caps' edges to flip in *cap_edges.
TinMesh::FaceHandle FoldedOrCapEdges(const TinMesh& mesh, const FacesBefore& before,
                                     std::vector<TinMesh::EdgeHandle>* cap_edges) {
  TinMesh::FaceHandle failed;
  for (size_t i = 0; i < before.faces.size() && !failed.is_valid(); ++i) {
    const auto fh = mesh.face_handle(before.faces[i]);
    std::array<TinMesh::HalfedgeHandle, 3> by_length;
    if (!DegenerateFace(mesh, fh, kCapHeight, &by_length)) {
      if (UnitFaceNormal(mesh, fh).dot(before.normal[i]) < 0.5) failed = fh;
      continue;
    }
    const auto longest = by_length[2];
    const auto edge = mesh.edge_handle(longest);
    if (mesh.is_boundary(edge) || !mesh.is_flip_ok(edge)) {
      failed = fh;
      continue;
    }
    if (!CapFlipsWell(mesh, fh, longest, before)) failed = fh;
    cap_edges->push_back(edge);
  }
  return failed;
}

void FlipCaps(TinMesh* mesh, const std::vector<TinMesh::EdgeHandle>& cap_edges) {
  for (auto edge : cap_edges) {
    mesh->flip(edge);
    for (int side : {0, 1}) {
      const auto fh = mesh->face_handle(mesh->halfedge_handle(edge, side));
      mesh->set_normal(fh, mesh->calc_face_normal(fh));
    }
  }
}

// The chain position of a corner of the failed face that moved most (and does not
// stay yet), -1 when none moved.
int WorstCorner(const TinMesh& mesh, TinMesh::FaceHandle failed, const std::vector<int>& chain,
                const std::vector<bool>& stays, const std::vector<double>& moved_by) {
  int worst = -1;
  for (auto fv : mesh.fv_range(failed)) {
    const auto it = std::find(chain.begin(), chain.end(), fv.idx());
    if (it == chain.end()) continue;
    const size_t c = it - chain.begin();
    if (!stays[c] && moved_by[c] > 0.0 && (worst < 0 || moved_by[c] > moved_by[worst])) worst = static_cast<int>(c);
  }
  return worst;
}

// Puts the chain onto the line, flipping the caps it makes, and undoes the moves when
// a face turns over. A chain that zigzags tightly across the line (a fine TIN over a
// ridge) often has one vertex whose move would fold a face or make a cap that cannot
// be flipped; the run is not dropped for it: that vertex stays where it is and the
// rest go onto the line, up to a third of the chain left off.
void LayChainOnLine(TinMesh* mesh, const std::vector<int>& chain, const Line& line, double h,
                    StraightenReport* report) {
  FacesBefore before;
  for (int v : chain) {
    for (auto fh : mesh->vf_range(mesh->vertex_handle(v))) before.faces.push_back(fh.idx());
  }
  std::sort(before.faces.begin(), before.faces.end());
  before.faces.erase(std::unique(before.faces.begin(), before.faces.end()), before.faces.end());
  for (int f : before.faces) before.normal.push_back(UnitFaceNormal(*mesh, mesh->face_handle(f)));
  std::vector<bool> stays(chain.size(), false);
  const int max_left = static_cast<int>(chain.size()) / 3;
  int left = 0;
  while (true) {
    const ChainMove move = MoveChainOntoLine(mesh, chain, stays, line, h);
    std::vector<TinMesh::EdgeHandle> cap_edges;
    const TinMesh::FaceHandle failed = FoldedOrCapEdges(*mesh, before, &cap_edges);
    if (!failed.is_valid()) {
      FlipCaps(mesh, cap_edges);
      report->flipped += static_cast<int>(cap_edges.size());
      report->moved += static_cast<int>(move.old.size());
      report->left_off += left;
      report->max_move = std::max(report->max_move, move.max_move);
      return;
    }
    for (const auto& [v, p] : move.old) mesh->set_point(mesh->vertex_handle(v), p);
    // The failed face's corner that moved most stays where it was, and the run is tried again.
    const int worst = WorstCorner(*mesh, failed, chain, stays, move.moved_by);
    if (worst < 0 || left == max_left) {
      ++report->rejected;
      return;
    }
    stays[worst] = true;
    ++left;
  }
}

// Straightens one candidate run (or counts why not).
void StraightenRun(TinMesh* mesh, const Candidate& candidate, int min_edges, double max_offset,
                   StraightenReport* report) {
  const double h = candidate.h;
  std::vector<int> kept = candidate.vertices;
  Line line;
  if (!FitRunLine(*mesh, h, max_offset, &kept, &line)) {
    ++report->too_small;
    return;
  }
  auto along = [&](int v) { return line.Along(VertexPoint(*mesh, v)); };
  int first = kept.front();
  double t_max = along(first);
  for (int v : kept) {
    if (along(v) < along(first)) first = v;
    t_max = std::max(t_max, along(v));
  }
  if (t_max - along(first) < min_edges * h * 0.9) {
    ++report->too_short;
    return;
  }
  const double t_min = along(first);
  SidePlanes planes;
  if (!FitSidePlanes(*mesh, kept, line, h, t_min, t_max, candidate.whole_set, &planes)) {
    ++report->sides_not_planar;
    return;
  }
  if (!LineWherePlanesMeet(planes, h, &line)) {
    ++report->sides_not_meeting;
    return;
  }
  ++report->components;
  const std::vector<int> chain = FollowChain(*mesh, kept, line, h, max_offset, candidate.whole_set);
  if (chain.size() < 3) {
    ++report->no_chain;
    return;
  }
  LayChainOnLine(mesh, chain, line, h, report);
}

}  // namespace

StraightenReport StraightenCreaseChains(TinMesh* mesh, const std::vector<bool>& crease_edge, int min_edges,
                                        double max_offset) {
  StraightenReport report;
  const std::vector<Candidate> candidates = CandidateRuns(*mesh, crease_edge, min_edges, max_offset, &report);
  for (const Candidate& candidate : candidates) StraightenRun(mesh, candidate, min_edges, max_offset, &report);
  if (report.moved > 0) UpdateVertexNormals(mesh);
  return report;
}

}  // namespace facets
