#include "mesh/surface_validity.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <string>

#include "mesh/local_ops.h"

namespace facets {
namespace {

// (cells + 1) x (cells + 1) grid of 1 m over z = 0; by default 5 x 5, whose centre vertex is interior.
TinMesh Grid(int cells = 4) {
  StartGridOptions grid;
  grid.min = Eigen::Vector2d(0, 0);
  grid.max = Eigen::Vector2d(cells, cells);
  grid.spacing = 1.0;
  return MakeStartGrid(grid);
}

// The grid vertex at (x, y); invalid when there is none.
TinMesh::VertexHandle VertexAt(const TinMesh& mesh, double x, double y) {
  for (auto v : mesh.vertices()) {
    const auto p = mesh.point(v);
    if (std::abs(p[0] - x) < 1e-9 && std::abs(p[1] - y) < 1e-9) return v;
  }
  return TinMesh::VertexHandle();
}

TinMesh::VertexHandle Centre(const TinMesh& mesh) { return VertexAt(mesh, 2, 2); }

std::vector<Eigen::Vector3d> Points(const TinMesh& mesh) {
  std::vector<Eigen::Vector3d> p;
  for (auto v : mesh.vertices()) p.push_back(ToEigen(mesh.point(v)));
  return p;
}

TEST(SurfaceValidity, FlatGridIsValid) {
  const TinMesh mesh = Grid();
  EXPECT_EQ(CountFoldedFaces(mesh), 0);
  EXPECT_EQ(CountSelfIntersections(mesh), 0);
}

TEST(SurfaceValidity, VertexDraggedAcrossItsRingFoldsAndTheGuardUndoesIt) {
  TinMesh mesh = Grid();
  const std::vector<Eigen::Vector3d> before = Points(mesh);
  const auto c = Centre(mesh);
  ASSERT_TRUE(c.is_valid());
  // 1.5 m sideways in the plane: past its neighbour at (3, 2), its triangles turn over.
  mesh.set_point(c, ToOpenMesh(Eigen::Vector3d(3.5, 2.0, 0.0)));
  const int folded = CountFoldedFaces(mesh);
  EXPECT_GT(folded, 0);
  const int limited = LimitFoldingSteps(&mesh, before);
  EXPECT_GT(limited, 0);
  EXPECT_EQ(CountFoldedFaces(mesh), 0);
  EXPECT_EQ(CountSelfIntersections(mesh), 0);
  // The step was halved, not necessarily undone: the vertex moved towards (3.5, 2).
  EXPECT_GE(mesh.point(c)[0], 2.0);
  EXPECT_LT(mesh.point(c)[0], 3.0);
}

// Two steps: the centre lifted 0.3 m (no fold), then dragged across its ring. The
// crossings carried from the first step give the second the same decisions as testing
// its start afresh.
TEST(SurfaceValidity, CarriedCrossingsGiveTheSameGuardedSteps) {
  TinMesh fresh = Grid();
  TinMesh carried = Grid();
  const auto c = Centre(fresh);
  ASSERT_TRUE(c.is_valid());
  KnownCrossings crossings;
  std::vector<int> limited;
  for (const Eigen::Vector3d& target : {Eigen::Vector3d(2.0, 2.0, 0.3), Eigen::Vector3d(3.5, 2.0, 0.3)}) {
    const std::vector<Eigen::Vector3d> before = Points(fresh);
    fresh.set_point(c, ToOpenMesh(target));
    carried.set_point(c, ToOpenMesh(target));
    const int limited_fresh = LimitFoldingSteps(&fresh, before);
    const int limited_carried = LimitFoldingSteps(&carried, before, kFoldGuardHalvings, &crossings);
    EXPECT_EQ(limited_carried, limited_fresh);
    limited.push_back(limited_carried);
    EXPECT_EQ(Points(carried), Points(fresh));
    // Both steps end clean (the drag halved), so the last test's pairs are kept.
    EXPECT_TRUE(crossings.known);
    EXPECT_EQ(static_cast<int>(crossings.pairs.size()), CountSelfIntersections(carried));
  }
  EXPECT_EQ(limited[0], 0);
  EXPECT_GT(limited[1], 0);
}

// A step halved twice on a 9 x 9 grid that already crosses itself elsewhere: the rounds
// after the first test only the faces near the halved vertices, and the pairs they leave
// are those of the whole surface, the old crossing far away among them.
TEST(SurfaceValidity, HalvedRoundsKeepTheCrossingsFarAway) {
  TinMesh mesh = Grid(8);
  const auto far = VertexAt(mesh, 6, 6), moved = VertexAt(mesh, 2, 2);
  ASSERT_TRUE(far.is_valid() && moved.is_valid());
  mesh.set_point(far, ToOpenMesh(Eigen::Vector3d(7.5, 6.0, 0.0)));  // across its ring: an old crossing
  const int old_pairs = CountSelfIntersections(mesh);
  ASSERT_GT(old_pairs, 0);
  const std::vector<Eigen::Vector3d> before = Points(mesh);
  // 3 m sideways: folded at 5 and 3.5, inside its ring at 2.75.
  mesh.set_point(moved, ToOpenMesh(Eigen::Vector3d(5.0, 2.0, 0.0)));
  KnownCrossings crossings;
  EXPECT_GT(LimitFoldingSteps(&mesh, before, kFoldGuardHalvings, &crossings), 0);
  EXPECT_NEAR(mesh.point(moved)[0], 2.75, 1e-12);
  EXPECT_EQ(mesh.point(far), ToOpenMesh(before[far.idx()]));
  ASSERT_TRUE(crossings.known);
  EXPECT_EQ(static_cast<int>(crossings.pairs.size()), CountSelfIntersections(mesh));
  EXPECT_EQ(static_cast<int>(crossings.pairs.size()), old_pairs);
}

TEST(SurfaceValidity, UnseenVertexRelaxesToItsRing) {
  TinMesh mesh = Grid();
  const auto c = Centre(mesh);
  mesh.set_point(c, ToOpenMesh(Eigen::Vector3d(2.0, 2.0, -3.0)));  // a pit nobody sees
  std::vector<int> views(mesh.n_vertices(), 5);
  views[c.idx()] = 0;
  EXPECT_EQ(RelaxUnseenVertices(&mesh, views), 1);
  EXPECT_NEAR(mesh.point(c)[2], 0.0, 1e-12);
}

TEST(SurfaceValidity, CrossingTrianglesAreUntangledLocally) {
  TinMesh mesh = Grid(8);
  const std::vector<Eigen::Vector3d> flat = Points(mesh);
  TinMesh::VertexHandle c;
  for (auto v : mesh.vertices()) {
    if ((ToEigen(mesh.point(v)) - Eigen::Vector3d(4, 4, 0)).norm() < 1e-9) c = v;
  }
  ASSERT_TRUE(c.is_valid());
  // Dragged past its neighbour at (5, 4) in the plane: its fan overlaps the
  // triangles beyond that neighbour, as two windows' steps can do between them.
  mesh.set_point(c, ToOpenMesh(Eigen::Vector3d(5.6, 4.3, 0.0)));
  const UntangleReport report = UntangleSelfIntersections(&mesh);
  EXPECT_GT(report.pairs_before, 0);
  EXPECT_EQ(report.pairs_after, 0);
  EXPECT_EQ(CountSelfIntersections(mesh), 0);
  // Local: nothing farther than 3 edges from the dragged vertex moved.
  const std::vector<Eigen::Vector3d> after = Points(mesh);
  int far_moved = 0;
  for (size_t i = 0; i < after.size(); ++i) {
    if ((flat[i] - Eigen::Vector3d(4, 4, 0)).lpNorm<Eigen::Infinity>() > 3.0 + 1e-9 &&
        (after[i] - flat[i]).norm() > 0.0) {
      ++far_moved;
    }
  }
  EXPECT_EQ(far_moved, 0);
  EXPECT_LE(report.vertices_moved, 49);
}

// Two tangles 10 m apart, the untangling confined to the vertices within 4 m of one of
// them (a trial's neighbourhood): that one is cleared, the other keeps its pairs and
// every vertex outside the mask stays where it was.
TEST(SurfaceValidity, ConfinedUntanglingLeavesTheOtherTangle) {
  TinMesh mesh = Grid(16);
  const auto near = VertexAt(mesh, 4, 4);
  const auto far = VertexAt(mesh, 12, 12);
  ASSERT_TRUE(near.is_valid() && far.is_valid());
  mesh.set_point(far, ToOpenMesh(Eigen::Vector3d(13.6, 12.3, 0.0)));
  const int far_pairs = CountSelfIntersections(mesh);
  ASSERT_GT(far_pairs, 0);
  mesh.set_point(near, ToOpenMesh(Eigen::Vector3d(5.6, 4.3, 0.0)));
  const int pairs = CountSelfIntersections(mesh);
  ASSERT_GT(pairs, far_pairs);
  const std::vector<Eigen::Vector3d> before = Points(mesh);
  std::vector<bool> movable(mesh.n_vertices(), false);
  for (auto v : mesh.vertices()) {
    movable[v.idx()] = (before[v.idx()] - Eigen::Vector3d(4, 4, 0)).lpNorm<Eigen::Infinity>() <= 4.0 + 1e-9;
  }
  const UntangleReport report = UntangleSelfIntersections(&mesh, 8, &movable);
  EXPECT_EQ(report.pairs_before, pairs);
  EXPECT_EQ(report.pairs_after, far_pairs);
  EXPECT_EQ(CountSelfIntersections(mesh), far_pairs);
  const std::vector<Eigen::Vector3d> after = Points(mesh);
  int outside_moved = 0;
  for (auto v : mesh.vertices()) outside_moved += !movable[v.idx()] && after[v.idx()] != before[v.idx()] ? 1 : 0;
  EXPECT_EQ(outside_moved, 0);
  EXPECT_GT(report.vertices_moved, 0);
  // Unconfined, the same untangling clears both.
  EXPECT_EQ(UntangleSelfIntersections(&mesh).pairs_after, 0);
}

// A pleat: a strip of faces folded flat over its neighbours (1-2 cm apart), as the
// finest level left it in a region one image sees (block region C, --thorough-walls,
// session 19; tests/data/pleat_patch.ply is the TIN 12 rings around its crossing
// faces). Three sweeps a round over a ring grown by one a round leave 7 of its 11 pairs
// after eight rounds; the membranes over them open it (before session 31, the rounds run
// nearly to convergence did: none left after 10 rounds, 76 vertices moved, at most 0.87 m).
TEST(SurfaceValidity, PleatFoldedFlatIsOpened) {
  TinMesh mesh = LoadStartMesh(std::string(FACETS_SOURCE_DIR) + "/tests/data/pleat_patch.ply");
  const std::vector<Eigen::Vector3d> before = Points(mesh);
  const UntangleReport report = UntangleSelfIntersections(&mesh);
  double max_move = 0.0;
  const std::vector<Eigen::Vector3d> after = Points(mesh);
  for (size_t i = 0; i < after.size(); ++i) max_move = std::max(max_move, (after[i] - before[i]).norm());
  std::cout << "pleat: " << report.pairs_before << " crossing pairs, " << report.pairs_after << " left after "
            << report.rounds << " rounds and " << report.membranes << " membranes, " << report.vertices_moved << " of "
            << mesh.n_vertices() << " vertices moved (max " << max_move << " m)\n";
  // Measured: 11 pairs, none left after 8 rounds and 1 membrane, 76 of 270 vertices moved
  // (max 1.31 m: the strip folded over, 0.8 m long, unfolds; the median edge is 0.53 m).
  EXPECT_EQ(report.pairs_before, 11);
  EXPECT_EQ(report.pairs_after, 0);
  EXPECT_EQ(CountSelfIntersections(mesh), 0);
  EXPECT_EQ(report.rounds, 8);  // no long sweeps needed
  EXPECT_GE(report.membranes, 1);
  EXPECT_LT(max_move, 1.6);  // three edges at most
  EXPECT_LE(report.vertices_moved, 100);
}

// The smoothing can spread a tangle rather than undo it (block A default, session 28:
// 45 pairs before the finest level's untangling, 68 after). The same pleat given one
// round (two with the extra one): 12 pairs after them (measured with session 28's build),
// one more than it came with; the membrane then starts from the best round's points, here
// the ones it came with, and opens the pleat (measured: 11 pairs, none left after one
// membrane, 26 vertices moved, the farthest 1.35 m: the strip folded over unfolds,
// where the sweeps of eight rounds moved it 0.87 m).
TEST(SurfaceValidity, MembraneOpensAPleatTheSweepsLeave) {
  TinMesh mesh = LoadStartMesh(std::string(FACETS_SOURCE_DIR) + "/tests/data/pleat_patch.ply");
  const std::vector<Eigen::Vector3d> before = Points(mesh);
  const UntangleReport report = UntangleSelfIntersections(&mesh, 1);
  EXPECT_EQ(report.pairs_before, 11);
  EXPECT_EQ(report.pairs_after, 0);
  EXPECT_EQ(CountSelfIntersections(mesh), 0);
  EXPECT_GE(report.membranes, 1);
  EXPECT_FALSE(report.kept_best_round);
  double max_move = 0.0;
  const std::vector<Eigen::Vector3d> after = Points(mesh);
  for (size_t i = 0; i < after.size(); ++i) max_move = std::max(max_move, (after[i] - before[i]).norm());
  EXPECT_LT(max_move, 1.6);  // three edges at most
  EXPECT_LE(report.vertices_moved, 40);
}

// A horn: a strip collapsed onto a line 1.2 m above a gable building's ridge end, as the
// finest level of block A (--thorough-walls, Embree AVX2, session 30) left it after its
// lips; tests/data/horn_patch.ply is the TIN 12 rings around its 16 crossing pairs
// (origin 2 6 9: the ridge runs along y at x = 0, z = -0.14, and ends at y = 0). The
// sweeps alone (session 30's build) left 14 pairs and sagged the ridge: 125 vertices moved,
// the farthest 2.74 m. The membranes open it (measured: none left, 30 vertices moved, the
// farthest 1.27 m, the horn's tip).
TEST(SurfaceValidity, HornOverARidgeEndIsOpenedWithoutSaggingTheRidge) {
  TinMesh mesh = LoadStartMesh(std::string(FACETS_SOURCE_DIR) + "/tests/data/horn_patch.ply");
  const std::vector<Eigen::Vector3d> before = Points(mesh);
  const UntangleReport report = UntangleSelfIntersections(&mesh);
  EXPECT_EQ(report.pairs_before, 16);
  EXPECT_EQ(report.pairs_after, 0);
  EXPECT_EQ(CountSelfIntersections(mesh), 0);
  EXPECT_GE(report.membranes, 1);
  EXPECT_LE(report.vertices_moved, 40);
  // The ridge half a metre and more before its end stays where it was.
  const std::vector<Eigen::Vector3d> after = Points(mesh);
  double ridge_move = 0.0, max_move = 0.0;
  for (size_t i = 0; i < after.size(); ++i) {
    const double move = (after[i] - before[i]).norm();
    max_move = std::max(max_move, move);
    if (before[i].y() < -0.5 && std::abs(before[i].x()) < 1.0 && before[i].z() > -1.0) ridge_move = std::max(ridge_move, move);
  }
  std::cout << "horn: " << report.pairs_before << " pairs, " << report.pairs_after << " left, " << report.membranes
            << " membranes, " << report.vertices_moved << " vertices moved (max " << max_move << " m, on the ridge "
            << ridge_move << " m)\n";
  EXPECT_LT(max_move, 1.5);
  EXPECT_LT(ridge_move, 0.05);
}

}  // namespace
}  // namespace facets
