#include "mesh/surface_validity.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

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

std::set<std::pair<int, int>> SelfIntersectingPairs(const TinMesh& mesh,
                                                    const std::vector<Eigen::Vector3d>& points) {
  CgalMesh cgal;
  for (auto v : mesh.vertices()) {
    const Eigen::Vector3d& p = points[v.idx()];
    cgal.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z()));  // index = v.idx()
  }
  // CGAL face index = TIN face index: faces added in order.
  for (auto f : mesh.faces()) {
    CgalMesh::Vertex_index t[3];
    int k = 0;
    for (auto v : mesh.fv_range(f)) t[k++] = CgalMesh::Vertex_index(static_cast<CgalMesh::size_type>(v.idx()));
    cgal.add_face(t[0], t[1], t[2]);
  }
  std::vector<std::pair<CgalMesh::Face_index, CgalMesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(cgal, std::back_inserter(pairs));
  std::set<std::pair<int, int>> result;
  for (const auto& [a, b] : pairs) {
    const int i = static_cast<int>(a), j = static_cast<int>(b);
    result.emplace(std::min(i, j), std::max(i, j));
  }
  return result;
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

int LimitFoldingSteps(TinMesh* mesh, const std::vector<Eigen::Vector3d>& before, int halvings) {
  const std::vector<Eigen::Vector3d> normals_before = FaceNormals(*mesh, before);
  std::vector<bool> folded_before(mesh->n_faces(), false);
  for (auto f : mesh->faces()) folded_before[f.idx()] = Folded(*mesh, normals_before, f);
  const std::set<std::pair<int, int>> crossing_before = SelfIntersectingPairs(*mesh, before);
  std::vector<bool> limited(mesh->n_vertices(), false);
  for (int round = 0; round <= halvings; ++round) {
    const std::vector<Eigen::Vector3d> points = Points(*mesh);
    const std::vector<Eigen::Vector3d> normals = FaceNormals(*mesh, points);
    std::vector<bool> shrink(mesh->n_vertices(), false);
    bool any = false;
    // Triangles that now cross where they did not before.
    for (const auto& pair : SelfIntersectingPairs(*mesh, points)) {
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
    if (!any) break;
    for (auto v : mesh->vertices()) {
      if (!shrink[v.idx()]) continue;
      limited[v.idx()] = true;
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

}  // namespace

UntangleReport UntangleSelfIntersections(TinMesh* mesh, int max_rounds) {
  UntangleReport report;
  std::set<std::pair<int, int>> pairs = SelfIntersectingPairs(*mesh, Points(*mesh));
  report.pairs_before = report.pairs_after = static_cast<int>(pairs.size());
  // The smoothing can spread a tangle instead of undoing it (block A default, session 28:
  // 45 pairs before the finest level's untangling, 68 after): the points of the round with
  // the fewest pairs (the later of equals) are what it returns.
  const std::vector<Eigen::Vector3d> original = Points(*mesh);
  std::vector<Eigen::Vector3d> best = original;
  size_t best_pairs = pairs.size();
  auto remember_if_best = [&]() {
    report.pairs_after = static_cast<int>(pairs.size());
    if (pairs.size() <= best_pairs) {
      best_pairs = pairs.size();
      best = Points(*mesh);
    }
  };
  // Folded faces give G1 patches that curl through their neighbours' even where the
  // chord triangles do not cross: their corners are smoothed in the first round too.
  const std::vector<bool> folded = FoldedFaces(*mesh);
  const bool any_fold = std::find(folded.begin(), folded.end(), true) != folded.end();
  for (int round = 1; round <= max_rounds && (!pairs.empty() || (round == 1 && any_fold)); ++round) {
    report.rounds = round;
    std::vector<bool> seed(mesh->n_vertices(), false);
    if (round == 1) {
      for (auto f : mesh->faces()) {
        if (!folded[f.idx()]) continue;
        for (auto v : mesh->fv_range(f)) seed[v.idx()] = true;
      }
    }
    // A crossing that survived smoothing its own corners needs a wider patch.
    SmoothRegion(mesh, CrossingRegion(*mesh, pairs, round - 1, std::move(seed)), 3);
    pairs = SelfIntersectingPairs(*mesh, Points(*mesh));
    remember_if_best();
  }
  // A pleat (a strip of faces folded flat over its neighbours, where one image or none
  // sees the surface) outlasts three sweeps a round: its vertices need the smoothing
  // run nearly to convergence over a patch around it (session 20: 11 and 4 pairs left
  // in two runs, none after 3-4 of these rounds). Runs only when the rounds above failed.
  for (int extra = 1; extra <= max_rounds && !pairs.empty(); ++extra) {
    report.rounds = max_rounds + extra;
    const int sweeps = 3 * (extra + 1) * (extra + 1);
    const std::vector<bool> region = CrossingRegion(*mesh, pairs, extra, std::vector<bool>(mesh->n_vertices(), false));
    SmoothRegion(mesh, region, sweeps);
    pairs = SelfIntersectingPairs(*mesh, Points(*mesh));
    remember_if_best();
  }
  if (static_cast<size_t>(report.pairs_after) > best_pairs) {
    for (auto vh : mesh->vertices()) mesh->set_point(vh, ToOpenMesh(best[vh.idx()]));
    report.pairs_after = static_cast<int>(best_pairs);
    report.kept_best_round = true;
  }
  for (auto vh : mesh->vertices()) report.vertices_moved += best[vh.idx()] != original[vh.idx()] ? 1 : 0;
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
