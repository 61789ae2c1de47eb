#include "mesh/tessellation.h"

#include <gtest/gtest.h>

#include <iostream>
#include <random>
#include <set>

#include "mesh/subdivision.h"
#include "mesh/test_util.h"

namespace facets {
namespace {

using Eigen::Vector3d;

TEST(Tessellation, SubTriangleMapRoundTrips) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  double max_err = 0;
  for (int t = 0; t < 100000; ++t) {
    double b1 = uni(rng), b2 = uni(rng);
    if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
    if (t < 15) b1 = (t % 5) / 4.0, b2 = (t / 5) / 4.0;  // lattice nodes too
    if (b1 + b2 > 1) continue;
    const Vector3d b(1 - b1 - b2, b1, b2);
    const SubTriangleLocation loc = LocateSubTriangle(b);
    ASSERT_GE(loc.k, 0);
    ASSERT_LT(loc.k, kSubTrianglesPerFace);
    EXPECT_GE(loc.u, -1e-12);
    EXPECT_GE(loc.v, -1e-12);
    EXPECT_LE(loc.u + loc.v, 1 + 1e-12);
    max_err = std::max(max_err, (FaceBarycentric(loc.k, loc.u, loc.v) - b).norm());
  }
  std::cout << "(face, b) -> (sub-triangle, u, v) -> b: max error " << max_err << "\n";
  EXPECT_LT(max_err, 1e-14);
  // Sub-triangles tile the face: areas sum to 1 (in barycentric units) and are CCW.
  double area = 0;
  for (int k = 0; k < kSubTrianglesPerFace; ++k) {
    const auto& c = SubTriangleCorners(k);
    const double a = (c[1][1] - c[0][1]) * (c[2][2] - c[0][2]) -
                     (c[1][2] - c[0][2]) * (c[2][1] - c[0][1]);
    EXPECT_NEAR(a, 1.0 / 16.0, 1e-15);
    area += a;
  }
  EXPECT_NEAR(area, 1.0, 1e-14);
}

void CheckTessellation(const TinMesh& mesh, const char* name) {
  const Tessellation tess = Tessellate(mesh);
  const size_t v = mesh.n_vertices(), e = mesh.n_edges(), f = mesh.n_faces();
  std::cout << name << ": V=" << v << " E=" << e << " F=" << f << " -> " << tess.points.size()
            << " nodes (V+3E+3F=" << v + 3 * e + 3 * f << "), " << tess.triangles.size()
            << " sub-triangles\n";
  EXPECT_EQ(tess.points.size(), v + 3 * e + 3 * f);
  EXPECT_EQ(tess.triangles.size(), 16 * f);
  EXPECT_EQ(tess.NumFaces(), static_cast<int>(f));
  // Every node is used; every sub-triangle corner is the face's G1 point at the
  // sub-triangle's corner barycentrics (so shared nodes are consistent across faces).
  const auto patches = BuildPatches(mesh);
  std::vector<int> used(tess.points.size(), 0);
  double max_node = 0, min_orient = 1;
  std::set<std::pair<int, int>> directed;
  for (int s = 0; s < static_cast<int>(tess.triangles.size()); ++s) {
    const int face = s / 16, k = s % 16;
    const auto& c = SubTriangleCorners(k);
    const Eigen::Vector3i t = tess.triangles[s];
    for (int i = 0; i < 3; ++i) {
      ++used[t[i]];
      max_node = std::max(max_node,
                          (tess.points[t[i]] - patches[face].Evaluate(c[i][1], c[i][2])).norm());
      // Consistent orientation: each directed sub-edge appears once.
      EXPECT_TRUE(directed.insert({t[i], t[(i + 1) % 3]}).second);
    }
    const Vector3d n = (tess.points[t[1]] - tess.points[t[0]])
                           .cross(tess.points[t[2]] - tess.points[t[0]]).normalized();
    const Vector3d bc = (c[0] + c[1] + c[2]) / 3;
    min_orient = std::min(min_orient, n.dot(patches[face].Normal(bc[1], bc[2])));
  }
  for (int u : used) EXPECT_GT(u, 0);
  std::cout << "  max node vs G1 evaluation " << max_node
            << ", min cos(sub-triangle normal, G1 normal) " << min_orient << "\n";
  EXPECT_LT(max_node, 1e-14);
  EXPECT_GT(min_orient, 0.9);
  // Node -> (face, barycentric) map.
  for (size_t p = 0; p < tess.points.size(); ++p) {
    const Vector3d& b = tess.point_barycentric[p];
    EXPECT_LT((patches[tess.point_face[p]].Evaluate(b[1], b[2]) - tess.points[p]).norm(), 1e-15);
  }
}

TEST(Tessellation, CountsAndSharedNodesGrid) { CheckTessellation(testing::SphereCap(0.1), "sphere cap"); }

TEST(Tessellation, CountsAndSharedNodesClosed) {
  TinMesh mesh;
  const double r[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<TinMesh::VertexHandle> v;
  for (auto& p : r) v.push_back(mesh.add_vertex(TinMesh::Point(p[0], p[1], p[2])));
  const int f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                       {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (auto& t : f) mesh.add_face(v[t[0]], v[t[1]], v[t[2]]);
  UpdateVertexNormals(&mesh);
  CheckTessellation(mesh, "octahedron");
  CheckTessellation(QuaternarySubdivide(mesh), "octahedron level 1");
}

TEST(Tessellation, UpdatePointsKeepsIndices) {
  TinMesh mesh = testing::SphereCap(0.1);
  Tessellation tess = Tessellate(mesh);
  const auto triangles = tess.triangles;
  // Move vertices along their normals (what the engine does), then update.
  for (auto v : mesh.vertices()) {
    mesh.set_point(v, mesh.point(v) + 0.01 * std::sin(7.0 * v.idx()) * mesh.normal(v));
  }
  UpdateVertexNormals(&mesh);
  UpdateTessellationPoints(mesh, &tess);
  const Tessellation fresh = Tessellate(mesh);
  double max_diff = 0;
  for (size_t p = 0; p < tess.points.size(); ++p) {
    max_diff = std::max(max_diff, (tess.points[p] - fresh.points[p]).norm());
  }
  EXPECT_EQ(tess.triangles, triangles);
  EXPECT_EQ(tess.triangles, fresh.triangles);
  EXPECT_EQ(max_diff, 0.0);
}

}  // namespace
}  // namespace facets
