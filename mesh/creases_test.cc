#include "mesh/creases.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <set>

#include "mesh/tessellation.h"

namespace facets {
namespace {

constexpr double kSlope = 0.36397023426620234;  // tan(20 deg)

double GableHeight(double, double y) { return 2.0 - kSlope * std::abs(y); }

TinMesh GableMesh() {
  StartGridOptions grid;
  grid.min = Eigen::Vector2d(-4, -4);
  grid.max = Eigen::Vector2d(4, 4);
  grid.spacing = 1.0;  // the ridge y = 0 runs along grid vertices
  grid.height = GableHeight;
  return MakeStartGrid(grid);
}

double MaxHeightError(const TinMesh& mesh, const std::vector<G1Patch>& patches) {
  const Tessellation tess = Tessellate(mesh, patches);
  double worst = 0.0;
  for (const auto& p : tess.points) worst = std::max(worst, std::abs(p.z() - GableHeight(p.x(), p.y())));
  return worst;
}

TEST(Creases, GableRoofIsReproducedExactlyWithCreasesAndRoundedWithout) {
  const TinMesh mesh = GableMesh();
  const CornerNormals creases = ComputeCornerNormals(mesh, 30.0);
  EXPECT_EQ(creases.num_crease_edges, 8);      // the ridge: 8 unit edges
  EXPECT_EQ(creases.num_crease_vertices, 9);
  const double with = MaxHeightError(mesh, BuildPatches(mesh, creases));
  const double without = MaxHeightError(mesh, BuildPatches(mesh));
  std::cout << "max height error of the G1 surface on a 20-degree gable roof, 1 m grid: "
            << "with creases " << with << " m, without " << without << " m\n";
  EXPECT_LT(with, 1e-12);
  EXPECT_GT(without, 0.02);
}

TEST(Creases, NoCreaseMeansVertexNormalsAndTheSamePatches) {
  const TinMesh mesh = GableMesh();
  const CornerNormals none = ComputeCornerNormals(mesh, 180.0);
  EXPECT_EQ(none.num_crease_edges, 0);
  const auto a = BuildPatches(mesh, none);
  const auto b = BuildPatches(mesh);
  for (size_t f = 0; f < a.size(); ++f) {
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(a[f].vertex(i), b[f].vertex(i));  // same vertex order as FacePatch
      EXPECT_NEAR((a[f].vertex_normal(i) - b[f].vertex_normal(i)).norm(), 0.0, 1e-15);
    }
    EXPECT_NEAR((a[f].Evaluate(0.2, 0.3) - b[f].Evaluate(0.2, 0.3)).norm(), 0.0, 1e-15);
  }
}

// Across a crease edge the two faces' patches meet in the same straight chord (G0).
TEST(Creases, SurfaceIsContinuousAcrossCreaseEdges) {
  TinMesh mesh = GableMesh();
  // Make the roof irregular so that the crease chords are not axis-aligned.
  for (auto vh : mesh.vertices()) {
    auto p = mesh.point(vh);
    p[2] += 0.05 * std::sin(3.0 * p[0]) + 0.1 * p[0];
    mesh.set_point(vh, p);
  }
  UpdateVertexNormals(&mesh);
  const CornerNormals creases = ComputeCornerNormals(mesh, 30.0);
  ASSERT_GT(creases.num_crease_edges, 0);
  const auto patches = BuildPatches(mesh, creases);
  double worst = 0.0;
  for (auto eh : mesh.edges()) {
    if (!creases.crease_edge[eh.idx()]) continue;
    const auto h0 = mesh.halfedge_handle(eh, 0);
    const Eigen::Vector3d a = ToEigen(mesh.point(mesh.from_vertex_handle(h0)));
    const Eigen::Vector3d b = ToEigen(mesh.point(mesh.to_vertex_handle(h0)));
    for (int side = 0; side < 2; ++side) {
      const auto fh = mesh.face_handle(mesh.halfedge_handle(eh, side));
      const G1Patch& patch = patches[fh.idx()];
      // Barycentrics of the chord a + s (b - a) within this face.
      int ia = -1, ib = -1;
      for (int i = 0; i < 3; ++i) {
        if (patch.vertex(i) == a) ia = i;
        if (patch.vertex(i) == b) ib = i;
      }
      ASSERT_GE(ia, 0);
      ASSERT_GE(ib, 0);
      for (int k = 1; k < 50; ++k) {
        const double s = k / 50.0;
        Eigen::Vector3d bary = Eigen::Vector3d::Zero();
        bary[ia] = 1.0 - s;
        bary[ib] = s;
        const Eigen::Vector3d on_patch = patch.Evaluate(bary[1], bary[2]);
        worst = std::max(worst, (on_patch - (a + s * (b - a))).norm());
      }
    }
  }
  std::cout << "largest distance of a crease boundary curve from its chord: " << worst << " m\n";
  EXPECT_LT(worst, 1e-12);
}

}  // namespace
}  // namespace facets

namespace facets {
namespace {

TEST(Creases, GreyLatticeIsSplitAlongCreases) {
  const TinMesh mesh = GableMesh();
  const CornerNormals creases = ComputeCornerNormals(mesh, 30.0);
  const Tessellation split = Tessellate(mesh, BuildPatches(mesh, creases), creases);
  const size_t base = mesh.n_vertices() + 3 * mesh.n_edges() + 3 * mesh.n_faces();
  // 3 duplicated nodes per crease edge, one per further sector of the 9 ridge vertices.
  EXPECT_EQ(split.points.size(), base + 3 * 8 + 9);
  // Duplicates coincide with their originals: the surface stays watertight.
  const Tessellation plain = Tessellate(mesh, BuildPatches(mesh, creases));
  ASSERT_EQ(plain.triangles.size(), split.triangles.size());
  double worst = 0.0;
  for (size_t s = 0; s < split.triangles.size(); ++s) {
    for (int c = 0; c < 3; ++c) {
      worst = std::max(worst, (split.points[split.triangles[s][c]] - plain.points[plain.triangles[s][c]]).norm());
    }
  }
  EXPECT_LT(worst, 1e-12);
  // Faces on the two sides of the ridge share no grey node on it.
  for (auto eh : mesh.edges()) {
    if (!creases.crease_edge[eh.idx()]) continue;
    const int f0 = mesh.face_handle(mesh.halfedge_handle(eh, 0)).idx();
    const int f1 = mesh.face_handle(mesh.halfedge_handle(eh, 1)).idx();
    std::set<int> nodes0;
    for (int k = 0; k < kSubTrianglesPerFace; ++k)
      for (int c = 0; c < 3; ++c) nodes0.insert(split.triangles[f0 * kSubTrianglesPerFace + k][c]);
    for (int k = 0; k < kSubTrianglesPerFace; ++k)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(nodes0.count(split.triangles[f1 * kSubTrianglesPerFace + k][c]), 0u);
  }
}

}  // namespace
}  // namespace facets
