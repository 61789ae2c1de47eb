#include "mesh/surface_validity.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>

#include <Eigen/Geometry>
#include <Eigen/Sparse>

#include <algorithm>
#include <iterator>
#include <set>
#include <utility>

namespace facets {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;

// Unit face normals from positions indexed by vertex (zero for degenerate faces).
std::vector<Eigen::Vector3d> FaceNormals(const TinMesh& mesh, const std::vector<Eigen::Vector3d>& points) {
  std::vector<Eigen::Vector3d> normals(mesh.n_faces(), Eigen::Vector3d::Zero());
  for (auto f : mesh.faces()) {
    Eigen::Vector3d x[3];
    int k = 0;
    for (auto v : mesh.fv_range(f)) x[k++] = points[v.idx()];
    const Eigen::Vector3d n = (x[1] - x[0]).cross(x[2] - x[0]);
    const double length = n.norm();
    if (length > 0.0) normals[f.idx()] = n / length;
  }
  return normals;
}

std::vector<Eigen::Vector3d> Points(const TinMesh& mesh) {
  std::vector<Eigen::Vector3d> points(mesh.n_vertices());
  for (auto v : mesh.vertices()) points[v.idx()] = ToEigen(mesh.point(v));
  return points;
}

// A TIN's chord triangles as a CGAL mesh (vertex and face indices those of the TIN),
// built once and tested again as its points move.
class ChordMesh {
 public:
  ChordMesh(const TinMesh& mesh, const std::vector<Eigen::Vector3d>& points) {
    for (auto v : mesh.vertices()) cgal_.add_vertex(ToCgal(points[v.idx()]));  // index = v.idx()
    // CGAL face index = TIN face index: faces added in order.
    for (auto f : mesh.faces()) {
      CgalMesh::Vertex_index t[3];
      int k = 0;
      for (auto v : mesh.fv_range(f)) t[k++] = CgalMesh::Vertex_index(static_cast<CgalMesh::size_type>(v.idx()));
      cgal_.add_face(t[0], t[1], t[2]);
    }
  }

  void Move(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& vertices) {
    for (int v : vertices) cgal_.point(CgalMesh::Vertex_index(static_cast<CgalMesh::size_type>(v))) = ToCgal(points[v]);
  }

  // The crossing pairs among `faces` (all faces when null).
  std::set<std::pair<int, int>> CrossingPairs(const std::vector<int>* faces) const {
    std::vector<std::pair<CgalMesh::Face_index, CgalMesh::Face_index>> pairs;
    if (faces) {
      std::vector<CgalMesh::Face_index> range;
      range.reserve(faces->size());
      for (int f : *faces) range.emplace_back(static_cast<CgalMesh::size_type>(f));
      CGAL::Polygon_mesh_processing::self_intersections(range, cgal_, std::back_inserter(pairs));
    } else {
      CGAL::Polygon_mesh_processing::self_intersections(cgal_, std::back_inserter(pairs));
    }
    std::set<std::pair<int, int>> result;
    for (const auto& [a, b] : pairs) {
      const int i = static_cast<int>(a), j = static_cast<int>(b);
      result.emplace(std::min(i, j), std::max(i, j));
    }
    return result;
  }

  // The faces whose boxes meet the box of a face of `changed` (those included): every
  // face that can cross one of them.
  std::vector<int> FacesMeeting(const std::vector<bool>& changed) const {
    std::vector<FaceBox> all, moved;
    all.reserve(cgal_.number_of_faces());
    for (auto f : cgal_.faces()) {
      all.emplace_back(Box(f), static_cast<int>(f));
      if (changed[static_cast<int>(f)]) moved.push_back(all.back());
    }
    std::vector<bool> meets(changed);
    CGAL::box_intersection_d(moved.begin(), moved.end(), all.begin(), all.end(),
                             [&meets](const FaceBox&, const FaceBox& b) { meets[b.info()] = true; });
    std::vector<int> faces;
    for (size_t f = 0; f < meets.size(); ++f) {
      if (meets[f]) faces.push_back(static_cast<int>(f));
    }
    return faces;
  }

 private:
  using FaceBox = CGAL::Box_intersection_d::Box_with_info_d<double, 3, int>;

  static Kernel::Point_3 ToCgal(const Eigen::Vector3d& p) { return Kernel::Point_3(p.x(), p.y(), p.z()); }

  CGAL::Bbox_3 Box(CgalMesh::Face_index f) const {
    CGAL::Bbox_3 box;
    for (auto v : cgal_.vertices_around_face(cgal_.halfedge(f))) box += cgal_.point(v).bbox();
    return box;
  }

  CgalMesh cgal_;
};

std::set<std::pair<int, int>> CrossingPairsAmong(const TinMesh& mesh, const std::vector<Eigen::Vector3d>& points,
                                                 const std::vector<int>* faces) {
  return ChordMesh(mesh, points).CrossingPairs(faces);
}

std::set<std::pair<int, int>> SelfIntersectingPairs(const TinMesh& mesh,
                                                    const std::vector<Eigen::Vector3d>& points) {
  return CrossingPairsAmong(mesh, points, nullptr);
}

bool Folded(const TinMesh& mesh, const std::vector<Eigen::Vector3d>& normals, TinMesh::FaceHandle f) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (auto g : mesh.ff_range(f)) mean += normals[g.idx()];
  return mean.squaredNorm() > 0.0 && normals[f.idx()].dot(mean) < 0.0;
}

}  // namespace

std::vector<bool> FoldedFaces(const TinMesh& mesh) {
  const std::vector<Eigen::Vector3d> normals = FaceNormals(mesh, Points(mesh));
  std::vector<bool> folded(mesh.n_faces(), false);
  for (auto f : mesh.faces()) folded[f.idx()] = Folded(mesh, normals, f);
  return folded;
}

int CountFoldedFaces(const TinMesh& mesh) {
  int count = 0;
  for (bool f : FoldedFaces(mesh)) count += f ? 1 : 0;
  return count;
}

int CountSelfIntersections(const TinMesh& mesh) {
  return static_cast<int>(SelfIntersectingPairs(mesh, Points(mesh)).size());
}

VertexMoves MeasureVertexMoves(const TinMesh& mesh, const std::vector<Eigen::Vector3d>& before, double least) {
  VertexMoves result;
  std::vector<double> moves;
  for (auto vh : mesh.vertices()) {
    const double d = (ToEigen(mesh.point(vh)) - before[vh.idx()]).norm();
    if (d >= least) moves.push_back(d);
  }
  result.moved = static_cast<int>(moves.size());
  if (!moves.empty()) {
    std::nth_element(moves.begin(), moves.begin() + moves.size() / 2, moves.end());
    result.median = moves[moves.size() / 2];
    result.max = *std::max_element(moves.begin(), moves.end());
  }
  return result;
}

namespace {

// The crossing pairs once the vertices `moved` went to `points`, from the pairs before
// the move: a pair of faces none of whose vertices moved stays as it was; the faces
// around the moved vertices are tested against every face whose box meets theirs.
// The same pairs as a test of the whole mesh, at the cost of the faces near the moves.
std::set<std::pair<int, int>> CrossingPairsAfterMoves(const TinMesh& mesh, ChordMesh* chords,
                                                      const std::vector<Eigen::Vector3d>& points,
                                                      const std::vector<int>& moved,
                                                      const std::set<std::pair<int, int>>& pairs_before) {
  chords->Move(points, moved);
  std::vector<bool> changed(mesh.n_faces(), false);
  for (int v : moved) {
    for (auto f : mesh.vf_range(mesh.vertex_handle(v))) changed[f.idx()] = true;
  }
  const std::vector<int> near = chords->FacesMeeting(changed);
  std::set<std::pair<int, int>> pairs = chords->CrossingPairs(&near);
  for (const auto& pair : pairs_before) {
    if (!changed[pair.first] && !changed[pair.second]) pairs.insert(pair);
  }
  return pairs;
}

}  // namespace

int LimitFoldingSteps(TinMesh* mesh, const std::vector<Eigen::Vector3d>& before, int halvings,
                      KnownCrossings* crossings) {
  const std::vector<Eigen::Vector3d> normals_before = FaceNormals(*mesh, before);
  std::vector<bool> folded_before(mesh->n_faces(), false);
  for (auto f : mesh->faces()) folded_before[f.idx()] = Folded(*mesh, normals_before, f);
  const bool carried = crossings && crossings->known;
  std::vector<int> moved(mesh->n_vertices());  // the vertices whose points the chords do not hold yet
  for (auto v : mesh->vertices()) moved[v.idx()] = v.idx();
  ChordMesh chords(*mesh, before);
  const std::set<std::pair<int, int>> crossing_before =
      carried ? std::move(crossings->pairs) : chords.CrossingPairs(nullptr);
  if (crossings) crossings->known = false;
  std::set<std::pair<int, int>> crossing_now;
  std::vector<bool> limited(mesh->n_vertices(), false);
  for (int round = 0; round <= halvings; ++round) {
    const std::vector<Eigen::Vector3d> points = Points(*mesh);
    const std::vector<Eigen::Vector3d> normals = FaceNormals(*mesh, points);
    std::vector<bool> shrink(mesh->n_vertices(), false);
    bool any = false;
    if (round == 0) {
      chords.Move(points, moved);
      crossing_now = chords.CrossingPairs(nullptr);
    } else {
      crossing_now = CrossingPairsAfterMoves(*mesh, &chords, points, moved, crossing_now);
    }
    // Triangles that now cross where they did not before.
    for (const auto& pair : crossing_now) {
      if (crossing_before.count(pair)) continue;
      any = true;
      for (int f : {pair.first, pair.second}) {
        for (auto v : mesh->fv_range(mesh->face_handle(f))) shrink[v.idx()] = true;
      }
    }
    for (auto f : mesh->faces()) {
      if (folded_before[f.idx()]) continue;  // an old fold may unfold; do not freeze it
      const bool bad = normals[f.idx()].dot(normals_before[f.idx()]) < 0.0 || Folded(*mesh, normals, f);
      if (!bad) continue;
      any = true;
      for (auto v : mesh->fv_range(f)) shrink[v.idx()] = true;
    }
    if (!any) {
      // The points stay as tested: their pairs are the next step's `before` pairs.
      if (crossings) *crossings = {std::move(crossing_now), true};
      break;
    }
    moved.clear();
    for (auto v : mesh->vertices()) {
      if (!shrink[v.idx()]) continue;
      limited[v.idx()] = true;
      moved.push_back(v.idx());
      const Eigen::Vector3d p = ToEigen(mesh->point(v));
      // The last round undoes the step: the surface before it was valid here.
      const Eigen::Vector3d q = round == halvings ? before[v.idx()] : before[v.idx()] + 0.5 * (p - before[v.idx()]);
      mesh->set_point(v, ToOpenMesh(q));
    }
  }
  int count = 0;
  for (bool l : limited) count += l ? 1 : 0;
  return count;
}

std::vector<bool> GrowByRings(const TinMesh& mesh, std::vector<bool> region, int rings) {
  for (int grow = 0; grow < rings; ++grow) {
    std::vector<bool> wider = region;
    for (auto v : mesh.vertices()) {
      if (!region[v.idx()]) continue;
      for (auto w : mesh.vv_range(v)) wider[w.idx()] = true;
    }
    region.swap(wider);
  }
  return region;
}

namespace {

// One round of the untangling: the free vertices of `region` move halfway to the mean of
// their neighbours, `sweeps` Jacobi sweeps. Returns the vertices moved.
std::vector<int> SmoothRegion(TinMesh* mesh, const std::vector<bool>& region, int sweeps) {
  std::vector<int> free;
  for (auto v : mesh->vertices()) {
    if (region[v.idx()] && !mesh->is_boundary(v) && mesh->valence(v) > 0) free.push_back(v.idx());
  }
  std::vector<Eigen::Vector3d> next(free.size());
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    for (size_t i = 0; i < free.size(); ++i) {
      const auto vh = mesh->vertex_handle(free[i]);
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      int count = 0;
      for (auto w : mesh->vv_range(vh)) {
        mean += ToEigen(mesh->point(w));
        ++count;
      }
      next[i] = 0.5 * (ToEigen(mesh->point(vh)) + mean / count);
    }
    for (size_t i = 0; i < free.size(); ++i) mesh->set_point(mesh->vertex_handle(free[i]), ToOpenMesh(next[i]));
  }
  return free;
}

// The vertices of the crossing faces, grown by `rings` rings.
std::vector<bool> CrossingRegion(const TinMesh& mesh, const std::set<std::pair<int, int>>& pairs, int rings,
                                 std::vector<bool> region) {
  for (const auto& pair : pairs) {
    for (int f : {pair.first, pair.second}) {
      for (auto v : mesh.fv_range(mesh.face_handle(f))) region[v.idx()] = true;
    }
  }
  return GrowByRings(mesh, std::move(region), rings);
}

// The widest membrane tried: the tangle grown by 4 rings.
constexpr int kMaxMembraneRings = 4;

// The crossing pairs grouped into tangles: pairs whose faces lie within two rings of
// each other belong to one.
std::vector<std::set<std::pair<int, int>>> Tangles(const TinMesh& mesh, const std::set<std::pair<int, int>>& pairs) {
  const std::vector<bool> near = CrossingRegion(mesh, pairs, 1, std::vector<bool>(mesh.n_vertices(), false));
  std::vector<int> component(mesh.n_vertices(), -1);
  int components = 0;
  for (auto seed : mesh.vertices()) {
    if (!near[seed.idx()] || component[seed.idx()] >= 0) continue;
    std::vector<TinMesh::VertexHandle> stack{seed};
    component[seed.idx()] = components;
    while (!stack.empty()) {
      const auto v = stack.back();
      stack.pop_back();
      for (auto w : mesh.vv_range(v)) {
        if (!near[w.idx()] || component[w.idx()] >= 0) continue;
        component[w.idx()] = components;
        stack.push_back(w);
      }
    }
    ++components;
  }
  std::vector<std::set<std::pair<int, int>>> tangles(components);
  for (const auto& pair : pairs) {
    const auto corner = *mesh.fv_range(mesh.face_handle(pair.first)).begin();
    tangles[component[corner.idx()]].insert(pair);
  }
  tangles.erase(std::remove_if(tangles.begin(), tangles.end(), [](const auto& t) { return t.empty(); }), tangles.end());
  return tangles;
}

// The faces a membrane over `region` can have changed the crossings of: those whose box,
// at the points `before` or now, meets the box of the region's vertices and their ring
// at either. Every face the membrane moved has its corners in that box, so every face
// that crosses one of them, before or after, meets the box too.
std::vector<int> FacesNearRegion(const TinMesh& mesh, const std::vector<bool>& region,
                                 const std::vector<Eigen::Vector3d>& before) {
  Eigen::AlignedBox3d box;
  for (auto v : mesh.vertices()) {
    if (!region[v.idx()]) continue;
    box.extend(before[v.idx()]).extend(ToEigen(mesh.point(v)));
    for (auto w : mesh.vv_range(v)) box.extend(before[w.idx()]).extend(ToEigen(mesh.point(w)));
  }
  std::vector<int> faces;
  for (auto f : mesh.faces()) {
    Eigen::AlignedBox3d face_box;
    for (auto v : mesh.fv_range(f)) face_box.extend(before[v.idx()]).extend(ToEigen(mesh.point(v)));
    if (face_box.intersects(box)) faces.push_back(f.idx());
  }
  return faces;
}

// The free vertices of `region` (not on the border) put where the uniform Laplacian
// vanishes, the vertices around the region held: the converged limit of SmoothRegion,
// solved at once. A strip collapsed onto a line (all its vertices and most of their
// neighbours on one segment) stays collapsed under the
// sweeps, whose means of collinear points are on the line again; the solve spans the
// membrane from the region's rim, which a ring or two out is off the line. Returns false
// (nothing moved) when the system cannot be solved.
bool SolveMembrane(TinMesh* mesh, const std::vector<bool>& region) {
  std::vector<int> index(mesh->n_vertices(), -1);
  std::vector<TinMesh::VertexHandle> free;
  for (auto v : mesh->vertices()) {
    if (!region[v.idx()] || mesh->is_boundary(v) || mesh->valence(v) == 0) continue;
    index[v.idx()] = static_cast<int>(free.size());
    free.push_back(v);
  }
  if (free.empty()) return false;
  const int n = static_cast<int>(free.size());
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
  for (int i = 0; i < n; ++i) {
    int degree = 0;
    for (auto w : mesh->vv_range(free[i])) {
      ++degree;
      if (index[w.idx()] >= 0) {
        entries.emplace_back(i, index[w.idx()], -1.0);
      } else {
        rhs.row(i) += ToEigen(mesh->point(w)).transpose();
      }
    }
    entries.emplace_back(i, i, static_cast<double>(degree));
  }
  Eigen::SparseMatrix<double> laplacian(n, n);
  laplacian.setFromTriplets(entries.begin(), entries.end());
  // Positive definite when every connected part of the region touches a held vertex;
  // a part that does not (a whole closed surface) makes the factorisation fail.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(laplacian);
  if (solver.info() != Eigen::Success) return false;
  const Eigen::MatrixXd x = solver.solve(rhs);
  if (solver.info() != Eigen::Success || !x.allFinite()) return false;
  for (int i = 0; i < n; ++i) mesh->set_point(free[i], ToOpenMesh(Eigen::Vector3d(x.row(i).transpose())));
  return true;
}

// The crossing pairs of an untangling and the points of the round with the fewest
// pairs so far (the later of equals), which are what it returns.
struct UntangleState {
  std::set<std::pair<int, int>> pairs;
  std::vector<Eigen::Vector3d> best;
  size_t best_pairs = 0;
  UntangleReport report;
  const std::vector<bool>* movable = nullptr;  // null: every vertex may move

  bool Movable(const TinMesh& mesh, int face) const {
    if (!movable) return true;
    for (auto v : mesh.fv_range(mesh.face_handle(face))) {
      if ((*movable)[v.idx()]) return true;
    }
    return false;
  }
  // The pairs the untangling works on: those with a movable corner. The others stay as
  // they are (no vertex of theirs moves), so the counts of the rounds differ by the same
  // number of pairs whether they are counted or not.
  std::set<std::pair<int, int>> Scoped(const TinMesh& mesh) const {
    if (!movable) return pairs;
    std::set<std::pair<int, int>> scoped;
    for (const auto& pair : pairs) {
      if (Movable(mesh, pair.first) || Movable(mesh, pair.second)) scoped.insert(pair);
    }
    return scoped;
  }
  std::vector<bool> Limit(std::vector<bool> region) const {
    if (!movable) return region;
    for (size_t v = 0; v < region.size(); ++v) region[v] = region[v] && (*movable)[v];
    return region;
  }

  void RememberIfBest(const TinMesh& mesh) {
    report.pairs_after = static_cast<int>(pairs.size());
    if (pairs.size() <= best_pairs) {
      best_pairs = pairs.size();
      best = Points(mesh);
    }
  }
};

// Membranes over one tangle grown by 1..kMaxMembraneRings rings: the first that leaves
// fewer pairs is kept (true); the others are undone.
bool TryMembranes(TinMesh* mesh, const std::set<std::pair<int, int>>& tangle, UntangleState* state) {
  for (int rings = 1; rings <= kMaxMembraneRings; ++rings) {
    const std::vector<Eigen::Vector3d> before = Points(*mesh);
    const std::vector<bool> region =
        state->Limit(CrossingRegion(*mesh, tangle, rings, std::vector<bool>(mesh->n_vertices(), false)));
    if (!SolveMembrane(mesh, region)) continue;
    ++state->report.membranes;
    // The pairs recounted among the faces near the region only (a tangle may get
    // up to 4 membranes a round: whole-mesh passes would cost seconds each time on
    // a tangled finest level); the pairs elsewhere are what they were.
    const std::vector<int> near = FacesNearRegion(*mesh, region, before);
    std::vector<bool> in_near(mesh->n_faces(), false);
    for (int f : near) in_near[f] = true;
    std::set<std::pair<int, int>> now = CrossingPairsAmong(*mesh, Points(*mesh), &near);
    for (const auto& pair : state->pairs) {
      if (!in_near[pair.first] || !in_near[pair.second]) now.insert(pair);
    }
    if (now.size() >= state->pairs.size()) {
      for (auto vh : mesh->vertices()) mesh->set_point(vh, ToOpenMesh(before[vh.idx()]));
      continue;
    }
    state->pairs = std::move(now);
    state->RememberIfBest(*mesh);
    return true;
  }
  return false;
}

// Still crossing after the smoothing rounds: each tangle (crossing pairs a ring or two
// apart) gets the membrane over it (TryMembranes), from the best points so far.
// Repeated while a round helps: a membrane that cuts a tangle down leaves a smaller
// one, whose own membrane can then finish it. Small regions only: a membrane flattens
// whatever real shape lies within it, and one over a wide region cuts through the
// walls around it (a pocket under a leaning wall went from 76 crossing pairs to 48
// with one ring, to 181-491 with 2-64). They run before the long sweeps, which run
// over regions grown by up to max_rounds rings and sag whatever lies in them (a horn
// over a gable's ridge end: the sweeps left 14 of 20 pairs and pulled the ridge's last
// 3 m down by up to 3.4 m; the membranes first left none and kept the ridge).
void MembraneRounds(TinMesh* mesh, int max_rounds, UntangleState* state) {
  for (auto vh : mesh->vertices()) mesh->set_point(vh, ToOpenMesh(state->best[vh.idx()]));
  state->pairs = SelfIntersectingPairs(*mesh, state->best);
  bool helped = true;
  for (int round = 0; round < max_rounds && helped; ++round) {
    const std::set<std::pair<int, int>> scoped = state->Scoped(*mesh);
    if (scoped.empty()) break;
    helped = false;
    for (const std::set<std::pair<int, int>>& tangle : Tangles(*mesh, scoped)) {
      if (TryMembranes(mesh, tangle, state)) helped = true;
    }
  }
}

}  // namespace

UntangleReport UntangleSelfIntersections(TinMesh* mesh, int max_rounds, const std::vector<bool>* movable) {
  UntangleState state;
  state.movable = movable;
  state.pairs = SelfIntersectingPairs(*mesh, Points(*mesh));
  state.report.pairs_before = state.report.pairs_after = static_cast<int>(state.pairs.size());
  // The smoothing can spread a tangle instead of undoing it (45 crossing pairs before a
  // finest level's untangling have become 68): the points of the round with the fewest
  // pairs are what it returns.
  const std::vector<Eigen::Vector3d> original = Points(*mesh);
  state.best = original;
  state.best_pairs = state.pairs.size();
  // Folded faces give G1 patches that curl through their neighbours' even where the
  // chord triangles do not cross: their corners are smoothed in the first round too.
  std::vector<bool> folded = FoldedFaces(*mesh);
  for (auto f : mesh->faces()) folded[f.idx()] = folded[f.idx()] && state.Movable(*mesh, f.idx());
  const bool any_fold = std::find(folded.begin(), folded.end(), true) != folded.end();
  for (int round = 1; round <= max_rounds; ++round) {
    const std::set<std::pair<int, int>> scoped = state.Scoped(*mesh);
    if (scoped.empty() && !(round == 1 && any_fold)) break;
    state.report.rounds = round;
    std::vector<bool> seed(mesh->n_vertices(), false);
    if (round == 1) {
      for (auto f : mesh->faces()) {
        if (!folded[f.idx()]) continue;
        for (auto v : mesh->fv_range(f)) seed[v.idx()] = true;
      }
    }
    // A crossing that survived smoothing its own corners needs a wider patch.
    SmoothRegion(mesh, state.Limit(CrossingRegion(*mesh, scoped, round - 1, std::move(seed))), 3);
    state.pairs = SelfIntersectingPairs(*mesh, Points(*mesh));
    state.RememberIfBest(*mesh);
  }
  if (state.best_pairs > 0) MembraneRounds(mesh, max_rounds, &state);
  // A pleat (a strip of faces folded flat over its neighbours, where one image or none
  // sees the surface) outlasts three sweeps a round: its vertices need the smoothing
  // run nearly to convergence over a patch around it (3-4 of these rounds cleared the
  // 4-11 pairs the short rounds left). Runs only when the rounds and the membranes
  // above failed.
  for (int extra = 1; extra <= max_rounds; ++extra) {
    const std::set<std::pair<int, int>> scoped = state.Scoped(*mesh);
    if (scoped.empty()) break;
    state.report.rounds = max_rounds + extra;
    const int sweeps = 3 * (extra + 1) * (extra + 1);
    const std::vector<bool> region =
        state.Limit(CrossingRegion(*mesh, scoped, extra, std::vector<bool>(mesh->n_vertices(), false)));
    SmoothRegion(mesh, region, sweeps);
    state.pairs = SelfIntersectingPairs(*mesh, Points(*mesh));
    state.RememberIfBest(*mesh);
  }
  UntangleReport& report = state.report;
  if (static_cast<size_t>(report.pairs_after) > state.best_pairs) {
    for (auto vh : mesh->vertices()) mesh->set_point(vh, ToOpenMesh(state.best[vh.idx()]));
    report.pairs_after = static_cast<int>(state.best_pairs);
    report.kept_best_round = true;
  }
  for (auto vh : mesh->vertices()) report.vertices_moved += state.best[vh.idx()] != original[vh.idx()] ? 1 : 0;
  return report;
}

GuardedStep GuardAndMeasureStep(TinMesh* mesh, const std::vector<Eigen::Vector3d>& before, double least) {
  GuardedStep step;
  step.limited = LimitFoldingSteps(mesh, before);
  step.moves = MeasureVertexMoves(*mesh, before, least);
  UpdateVertexNormals(mesh);
  return step;
}

}  // namespace facets
