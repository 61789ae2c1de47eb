#include "mesh/creases.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <cmath>
#include <iostream>
#include <set>

#include "mesh/local_ops.h"
#include "mesh/tessellation.h"
#include "mesh/test_util.h"

namespace facets {
namespace {

using ::facets::testing::GridMesh;

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

// A 20-degree gable whose ridge the curvature regularisation has rounded: the faces
// next to the ridge tilt by 8 degrees, the next row by 16, the roof beyond by 20. No
// edge bends by 20 degrees (the ridge row by 16, the others by 8 and 4), but across
// the ridge row's band the vertex normals enclose about 24: the ridge row, and only
// it, is a crease.
double RoundedRidgeHeight(double, double y) {
  const double t8 = std::tan(8.0 * M_PI / 180.0), t16 = std::tan(16.0 * M_PI / 180.0);
  const double a = std::abs(y);
  if (a <= 1.0) return 2.0 - t8 * a;
  if (a <= 2.0) return 2.0 - t8 - t16 * (a - 1.0);
  return 2.0 - t8 - t16 - kSlope * (a - 2.0);
}

TEST(Creases, RidgeRoundedOverABandOfRowsIsFoundInItsMiddleRow) {
  const TinMesh mesh = GridMesh(4, RoundedRidgeHeight);
  const std::vector<bool> crease = DetectCreaseEdges(mesh, 20.0, /*rounded_ridges=*/true);
  int found = 0, on_ridge = 0;
  for (auto eh : mesh.edges()) {
    if (!crease[eh.idx()]) continue;
    ++found;
    const auto h = mesh.halfedge_handle(eh, 0);
    if (std::abs(mesh.point(mesh.from_vertex_handle(h))[1]) < 1e-9 &&
        std::abs(mesh.point(mesh.to_vertex_handle(h))[1]) < 1e-9) {
      ++on_ridge;
    }
  }
  // The row y = 0 has 8 unit edges; the two at the ends have a corner on the grid's
  // border, whose half ring says nothing about the band.
  EXPECT_EQ(found, 6);
  EXPECT_EQ(on_ridge, 6);
  // At a crease angle of 30 degrees the band (about 24) is no crease.
  const std::vector<bool> none = DetectCreaseEdges(mesh, 30.0, true);
  // Without the band rule the 16-degree ridge row is no crease at 20 degrees.
  const std::vector<bool> plain = DetectCreaseEdges(mesh, 20.0, false);
  EXPECT_EQ(std::count(plain.begin(), plain.end(), true), 0);
  EXPECT_EQ(std::count(none.begin(), none.end(), true), 0);
}

// Smooth curvature and noise stay G1: a parabolic cylinder bending 3.4 degrees per
// 2 m (the seed's) sampled at 1 m, with 2 cm of height noise on every vertex.
TEST(Creases, SmoothCurvatureAndNoiseMakeNoCrease) {
  StartGridOptions grid;
  grid.min = Eigen::Vector2d(-6, -6);
  grid.max = Eigen::Vector2d(6, 6);
  grid.spacing = 1.0;
  grid.height = [](double x, double y) {
    const double noise = 0.02 * std::sin(12.9898 * x + 78.233 * y + 0.5 * x * y);
    return 3.0 - 0.0148 * y * y + noise;  // slope 2 * 0.0148 * y: 3.4 degrees per 2 m
  };
  const TinMesh mesh = MakeStartGrid(grid);
  const std::vector<bool> crease = DetectCreaseEdges(mesh, 20.0, /*rounded_ridges=*/true);
  EXPECT_EQ(std::count(crease.begin(), crease.end(), true), 0);
}

}  // namespace
}  // namespace facets
