#include "mesh/subdivision.h"

#include <gtest/gtest.h>

#include <iostream>

#include "mesh/test_util.h"

namespace facets {
namespace {

using Eigen::Vector3d;

TEST(QuaternarySubdivide, CountsAndLayout) {
  const TinMesh mesh = testing::SphereCap(0.25);
  const TinMesh fine = QuaternarySubdivide(mesh);
  EXPECT_EQ(fine.n_vertices(), mesh.n_vertices() + mesh.n_edges());
  EXPECT_EQ(fine.n_faces(), 4 * mesh.n_faces());
  EXPECT_EQ(fine.n_edges(), 2 * mesh.n_edges() + 3 * mesh.n_faces());
  // Old vertices keep their index and position; new ones sit on the G1 edge curve
  // midpoint, not the chord midpoint.
  for (auto v : mesh.vertices()) EXPECT_EQ(fine.point(fine.vertex_handle(v.idx())), mesh.point(v));
  double min_offset = 1e9;
  for (auto e : mesh.edges()) {
    const Vector3d m = ToEigen(fine.point(fine.vertex_handle(mesh.n_vertices() + e.idx())));
    EXPECT_LT((m - MakeEdgeCurve(mesh, e).Point(0.5)).norm(), 1e-15);
    const auto h = mesh.halfedge_handle(e, 0);
    const Vector3d chord_mid = 0.5 * ToEigen(mesh.point(mesh.from_vertex_handle(h)) +
                                             mesh.point(mesh.to_vertex_handle(h)));
    min_offset = std::min(min_offset, (m - chord_mid).norm());
  }
  EXPECT_GT(min_offset, 1e-4);
  // Child corners map to the parent's barycentrics.
  const auto patches = BuildPatches(mesh);
  double max_corner = 0;
  for (auto f : mesh.faces()) {
    for (int c = 0; c < 4; ++c) {
      int k = 0;
      for (auto v : fine.fv_range(fine.face_handle(4 * f.idx() + c))) {
        const Vector3d b = ChildCornerInParent(c, k++);
        max_corner = std::max(
            max_corner, (ToEigen(fine.point(v)) - patches[f.idx()].Evaluate(b[1], b[2])).norm());
      }
    }
  }
  EXPECT_LT(max_corner, 1e-14);
}

// Distance from y to the G1 patch, by Gauss-Newton from parent barycentrics b.
double DistanceToPatch(const G1Patch& patch, const Vector3d& y, Vector3d b) {
  double b1 = b[1], b2 = b[2];
  for (int it = 0; it < 20; ++it) {
    const SurfacePoint sp = patch.EvaluateWithDerivatives(b1, b2);
    Eigen::Matrix<double, 3, 2> j;
    j << sp.d_b1, sp.d_b2;
    const Eigen::Vector2d step = (j.transpose() * j).ldlt().solve(j.transpose() * (y - sp.point));
    b1 += step[0];
    b2 += step[1];
    if (step.norm() < 1e-15) break;
  }
  return (y - patch.Evaluate(b1, b2)).norm();
}

TEST(QuaternarySubdivide, KeepsTheShape) {
  for (double h : {0.2, 0.1}) {
    const TinMesh mesh = testing::SphereCap(h);
    const auto sphere = [](const Vector3d& p) { return p.norm() - 1.0; };
    const double old_error = testing::MaxSurfaceError(mesh, sphere).g1;
    const auto old_patches = BuildPatches(mesh);
    for (bool keep : {true, false}) {
      SubdivisionOptions opt;
      opt.keep_g1_normals = keep;
      const TinMesh fine = QuaternarySubdivide(mesh, opt);
      const auto fine_patches = BuildPatches(fine);
      double max_dev = 0;
      const int n = 8;
      for (int f = 0; f < static_cast<int>(fine.n_faces()); ++f) {
        const int parent = f / 4, child = f % 4;
        for (int j = 0; j <= n; ++j) {
          for (int i = 0; i + j <= n; ++i) {
            const Vector3d c(double(n - i - j) / n, double(i) / n, double(j) / n);
            const Vector3d y = fine_patches[f].Evaluate(c[1], c[2]);
            const Vector3d b = c[0] * ChildCornerInParent(child, 0) +
                               c[1] * ChildCornerInParent(child, 1) +
                               c[2] * ChildCornerInParent(child, 2);
            max_dev = std::max(max_dev, DistanceToPatch(old_patches[parent], y, b));
          }
        }
      }
      const double new_error = testing::MaxSurfaceError(fine, sphere).g1;
      std::cout << "h=" << h << (keep ? " G1 normals" : " mean face normals")
                << ": old error to sphere " << old_error << ", new surface vs old " << max_dev
                << " (" << 100 * max_dev / old_error << "%), new error to sphere " << new_error
                << "\n";
      if (keep) {
        EXPECT_LT(max_dev, 0.1 * old_error);
      }
    }
  }
}

}  // namespace
}  // namespace facets
