// Validity of a TIN as it turns from 2.5D into 3D: folded triangles, self-
// intersections, and a guard that limits vertex steps which would fold the surface.
#pragma once

#include <Eigen/Core>
#include <set>
#include <utility>
#include <vector>

#include "mesh/tin.h"

namespace facets {

// A face is folded when its normal points against the mean of its edge neighbours'
// normals (dot < 0): the surface turned back on itself there. Normals are computed
// from the points, not taken from the mesh.
std::vector<bool> FoldedFaces(const TinMesh& mesh);
int CountFoldedFaces(const TinMesh& mesh);

// Pairs of triangles that intersect other than in shared vertices or edges (CGAL
// Polygon_mesh_processing::self_intersections on the TIN's chord triangles).
int CountSelfIntersections(const TinMesh& mesh);

// Fold guard for one adjustment step: `before` holds the points before the step
// (one per vertex). A face that was not folded before and now is folded or has its
// normal reversed against its own normal before the step, and a pair of faces that
// intersect now but did not before, mark their vertices; their
// steps are halved, up to `halvings` times, and undone when the face is still bad.
// Vertex normals are not updated (the caller does). Returns the vertices limited.
// `crossings`, when given, carries the crossing face pairs from one step to the next of
// the same mesh: read as the pairs of `before` when known, left as the pairs of the
// final points when the last test saw them (no step needed halving after it), so a
// sequence of steps tests crossings once per step instead of twice. The halving rounds
// after the first test only the faces around the vertices just halved against the faces
// whose boxes meet theirs; the other pairs are kept (the same pairs as a whole test).
struct KnownCrossings {
  std::set<std::pair<int, int>> pairs;  // face index pairs, smaller index first
  bool known = false;
};
constexpr int kFoldGuardHalvings = 4;
int LimitFoldingSteps(TinMesh* mesh, const std::vector<Eigen::Vector3d>& before, int halvings = kFoldGuardHalvings,
                      KnownCrossings* crossings = nullptr);

// How far the vertices went from `before` (one point per vertex): those that moved at
// least `least` (m), their median and largest move. For the reports of steps that
// LimitFoldingSteps guarded.
struct VertexMoves {
  int moved = 0;
  double median = 0.0;
  double max = 0.0;
};
VertexMoves MeasureVertexMoves(const TinMesh& mesh, const std::vector<Eigen::Vector3d>& before, double least);

// The end of a step that moved vertices from `before` (one point per vertex): the fold
// guard (LimitFoldingSteps), the moves of at least `least` (m) measured, and the vertex
// normals updated. Shared by the searches between levels and the V-cycle's projection.
struct GuardedStep {
  int limited = 0;  // vertices whose steps the fold guard halved or undid
  VertexMoves moves;
};
GuardedStep GuardAndMeasureStep(TinMesh* mesh, const std::vector<Eigen::Vector3d>& before, double least);

// Into a step's report (any struct with limited, moved, median_move, max_move).
template <class Report>
void CopyStepFields(const GuardedStep& step, Report* report) {
  report->limited = step.limited;
  report->moved = step.moves.moved;
  report->median_move = step.moves.median;
  report->max_move = step.moves.max;
}

// `region` (one flag per vertex) with the vertices up to `rings` edges from it added.
std::vector<bool> GrowByRings(const TinMesh& mesh, std::vector<bool> region, int rings);

// Repair of crossings the per-window fold guard cannot see (between windows, after
// splits): the vertices of crossing triangles, and from round 2 on their rings grown by
// one per round, move halfway to the mean of their neighbours (three Jacobi sweeps per
// round), until no pair crosses or `max_rounds` is spent. Pairs still left: each tangle
// (crossings a ring or two apart) gets a membrane, the uniform Laplacian solved over it
// grown by 1..4 rings with the ring around held, the first that leaves fewer pairs kept,
// repeated up to `max_rounds` times while that helps (a strip collapsed onto a line stays
// on it under sweeps). Then, if pairs are left, up to `max_rounds` more rounds over the
// crossings grown by k rings with 3 (k + 1)^2 sweeps (near convergence; these sag what
// lies in their regions, hence last). Boundary vertices stay. The points of the round or
// membrane that left the fewest pairs are kept (never more than before).
// Vertex normals are not updated (the caller does). Returns the crossing pairs left.
// `movable` (one flag per vertex), when given, confines the untangling to a trial's
// neighbourhood: only the vertices it flags move, only the crossing pairs and folded faces
// with a flagged corner are worked on, and the pairs elsewhere are counted as they stand.
struct UntangleReport {
  int pairs_before = 0;
  int pairs_after = 0;
  int rounds = 0;          // smoothing rounds, the long ones counted after the first max_rounds
  int membranes = 0;       // membranes solved (kept or not)
  int vertices_moved = 0;  // vertices that end elsewhere than they began
  bool kept_best_round = false;  // the last round left more pairs than an earlier one, whose points were restored
};
UntangleReport UntangleSelfIntersections(TinMesh* mesh, int max_rounds = 8,
                                         const std::vector<bool>* movable = nullptr);

}  // namespace facets
