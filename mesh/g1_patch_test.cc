#include "mesh/g1_patch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "mesh/test_util.h"
#include "mesh/tin.h"

namespace facets {
namespace {

using Eigen::Vector3d;

// A curved triangle: three points on a sphere of radius 2 with exact normals.
G1Patch SphereTriangle() {
  const Vector3d x0 = Vector3d(0.3, -0.2, 2.0).normalized() * 2.0;
  const Vector3d x1 = Vector3d(1.1, 0.1, 1.6).normalized() * 2.0;
  const Vector3d x2 = Vector3d(0.4, 0.9, 1.7).normalized() * 2.0;
  return G1Patch(x0, x1, x2, x0, x1, x2);
}

TEST(G1Patch, InterpolatesVerticesAndNormals) {
  const G1Patch patch = SphereTriangle();
  const double corners[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  double max_near = 0.0;
  for (int i = 0; i < 3; ++i) {
    const SurfacePoint sp = patch.EvaluateWithDerivatives(corners[i][0], corners[i][1]);
    EXPECT_EQ((sp.point - patch.vertex(i)).norm(), 0.0);
    EXPECT_EQ((patch.Evaluate(corners[i][0], corners[i][1]) - patch.vertex(i)).norm(), 0.0);
    EXPECT_LT((sp.normal - patch.vertex_normal(i)).norm(), 1e-12);
    // Approaching the vertex from inside, the surface normal tends to N_i.
    const double eps = 1e-7;
    const double b1 = i == 1 ? 1 - 2 * eps : eps, b2 = i == 2 ? 1 - 2 * eps : eps;
    const SurfacePoint near = patch.EvaluateWithDerivatives(b1, b2);
    max_near = std::max(max_near, (near.normal - patch.vertex_normal(i)).norm());
    EXPECT_LT((near.point - patch.vertex(i)).norm(), 1e-6);
  }
  std::cout << "normal deviation at distance 1e-7 from the vertices: " << max_near << "\n";
  EXPECT_LT(max_near, 1e-5);
}

// A hair outside a corner, where rounding leaves b_i = 1 and b_j = -b_k ~ 1e-16 (the
// tangential smoothing located a vertex at its own ring's centroid like this, block
// scene with 5-pixel edges): the side-vertex parameter of P_i was 0/0 and the point NaN.
TEST(G1Patch, FiniteAHairOutsideACorner) {
  const G1Patch patch = SphereTriangle();
  for (const double tiny : {2.1837766987359469e-16, 1e-17, 3e-300}) {
    for (int i = 0; i < 3; ++i) {
      // b_i = 1 (as evaluated: b0 = 1 - b1 - b2), the two others +-tiny.
      const double b1 = i == 1 ? 1.0 : (i == 0 ? tiny : -tiny);
      const double b2 = i == 2 ? 1.0 : (i == 0 ? -tiny : tiny);
      const SurfacePoint sp = patch.EvaluateWithDerivatives(b1, b2);
      EXPECT_TRUE(sp.point.allFinite()) << "corner " << i << ", " << tiny;
      EXPECT_TRUE(sp.normal.allFinite()) << "corner " << i << ", " << tiny;
      EXPECT_LT((sp.point - patch.vertex(i)).norm(), 1e-12) << "corner " << i << ", " << tiny;
      EXPECT_LT((sp.normal - patch.vertex_normal(i)).norm(), 1e-6) << "corner " << i << ", " << tiny;
      EXPECT_LT((patch.Evaluate(b1, b2) - patch.vertex(i)).norm(), 1e-12) << "corner " << i << ", " << tiny;
    }
  }
}

TEST(G1Patch, ReproducesPlane) {
  const Vector3d n = Vector3d(0.3, -0.5, 0.8).normalized();
  Vector3d e1 = n.cross(Vector3d::UnitX()).normalized(), e2 = n.cross(e1);
  const Vector3d o(10.0, -3.0, 2.0);
  const Vector3d x0 = o, x1 = o + 1.3 * e1 + 0.2 * e2, x2 = o - 0.4 * e1 + 0.9 * e2;
  const G1Patch patch(x0, x1, x2, n, n, n);
  double max_dev = 0.0, max_param = 0.0, max_normal = 0.0;
  const int m = 20;
  for (int j = 0; j <= m; ++j) {
    for (int i = 0; i + j <= m; ++i) {
      const double b1 = double(i) / m, b2 = double(j) / m;
      const SurfacePoint sp = patch.EvaluateWithDerivatives(b1, b2);
      max_dev = std::max(max_dev, std::abs((sp.point - o).dot(n)));
      max_param = std::max(max_param, (sp.point - patch.EvaluateFlat(b1, b2)).norm());
      max_normal = std::max(max_normal, (sp.normal - n).norm());
    }
  }
  std::cout << "plane: max distance " << max_dev << ", max deviation from linear map "
            << max_param << ", max normal error " << max_normal << "\n";
  EXPECT_LT(max_dev, 1e-12);
  EXPECT_LT(max_param, 1e-12);
  EXPECT_LT(max_normal, 1e-12);
}

TEST(G1Patch, IndependentOfVertexOrder) {
  const Vector3d x[3] = {Vector3d(0, 0, 0.1), Vector3d(1, 0.1, -0.2), Vector3d(0.2, 1.1, 0.3)};
  const Vector3d n[3] = {Vector3d(0.1, 0.2, 1).normalized(), Vector3d(-0.3, 0.1, 1).normalized(),
                         Vector3d(0.2, -0.4, 1).normalized()};
  const G1Patch ref(x[0], x[1], x[2], n[0], n[1], n[2]);
  // Rotation (1, 2, 0) and reflection (0, 2, 1).
  const G1Patch rot(x[1], x[2], x[0], n[1], n[2], n[0]);
  const G1Patch ref2(x[0], x[2], x[1], n[0], n[2], n[1]);
  double max_point = 0.0, max_normal = 0.0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (int t = 0; t < 1000; ++t) {
    double b1 = uni(rng), b2 = uni(rng);
    if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
    const double b0 = 1 - b1 - b2;
    const SurfacePoint a = ref.EvaluateWithDerivatives(b1, b2);
    const SurfacePoint r = rot.EvaluateWithDerivatives(b2, b0);   // rot's (b1,b2)=(x2,x0)
    const SurfacePoint f = ref2.EvaluateWithDerivatives(b2, b1);  // ref2's (b1,b2)=(x2,x1)
    max_point = std::max({max_point, (a.point - r.point).norm(), (a.point - f.point).norm()});
    max_normal = std::max({max_normal, (a.normal - r.normal).norm(), (a.normal + f.normal).norm()});
  }
  std::cout << "vertex order: max point difference " << max_point << ", normal difference "
            << max_normal << "\n";
  EXPECT_LT(max_point, 1e-12);
  EXPECT_LT(max_normal, 1e-12);
}

TEST(G1Patch, AnalyticDerivativesMatchFiniteDifferences) {
  const G1Patch patch = SphereTriangle();
  double max_err = 0.0;
  const double h = 1e-6;
  for (double b1 : {0.1, 0.3, 0.5, 0.05}) {
    for (double b2 : {0.1, 0.2, 0.4}) {
      const SurfacePoint sp = patch.EvaluateWithDerivatives(b1, b2);
      const Vector3d fd1 = (patch.Evaluate(b1 + h, b2) - patch.Evaluate(b1 - h, b2)) / (2 * h);
      const Vector3d fd2 = (patch.Evaluate(b1, b2 + h) - patch.Evaluate(b1, b2 - h)) / (2 * h);
      max_err = std::max({max_err, (fd1 - sp.d_b1).norm(), (fd2 - sp.d_b2).norm()});
    }
  }
  std::cout << "max |analytic - central difference| derivative: " << max_err << "\n";
  EXPECT_LT(max_err, 1e-7);
}

TEST(EdgeCurve, ReversedIsSameCurve) {
  const Vector3d xa(0, 0, 0), xb(1, 0.2, 0.3);
  const Vector3d na = Vector3d(0.1, 0.3, 1).normalized(), nb = Vector3d(-0.4, 0, 1).normalized();
  const EdgeCurve ab(xa, na, xb, nb), ba(xb, nb, xa, na);
  double max_p = 0, max_n = 0;
  for (int i = 0; i <= 20; ++i) {
    const double s = i / 20.0;
    max_p = std::max(max_p, (ab.Point(s) - ba.Point(1 - s)).norm());
    max_n = std::max(max_n, (ab.Normal(s) - ba.Normal(1 - s)).norm());
    EXPECT_LT(std::abs(ab.Normal(s).dot(ab.Tangent(s))), 1e-12);
  }
  EXPECT_LT(max_p, 1e-14);
  EXPECT_LT(max_n, 1e-14);
  EXPECT_LT((ab.Normal(0) - na).norm(), 1e-15);
  EXPECT_LT((ab.Normal(1) - nb).norm(), 1e-15);
}

// G1 across every interior edge: both neighbouring patches give the same point and
// the same unit normal at 50 points per edge.
void CheckG1(const TinMesh& mesh, const char* name) {
  const std::vector<G1Patch> patches = BuildPatches(mesh);
  double max_normal = 0.0, max_point = 0.0, max_normal_jump_flat = 0.0;
  int edges = 0;
  for (auto e : mesh.edges()) {
    if (mesh.is_boundary(e)) continue;
    ++edges;
    const auto h0 = mesh.halfedge_handle(e, 0);
    const auto va = mesh.from_vertex_handle(h0), vb = mesh.to_vertex_handle(h0);
    const auto f0 = mesh.face_handle(h0), f1 = mesh.opposite_face_handle(h0);
    const int a0 = testing::LocalIndex(mesh, f0, va), b0 = testing::LocalIndex(mesh, f0, vb);
    const int a1 = testing::LocalIndex(mesh, f1, va), b1 = testing::LocalIndex(mesh, f1, vb);
    max_normal_jump_flat =
        std::max(max_normal_jump_flat, (mesh.normal(f0) - mesh.normal(f1)).norm());
    for (int m = 0; m < 50; ++m) {
      const double s = (m + 1) / 51.0;
      Vector3d bar0 = Vector3d::Zero(), bar1 = Vector3d::Zero();
      bar0[a0] = 1 - s;
      bar0[b0] = s;
      bar1[a1] = 1 - s;
      bar1[b1] = s;
      const SurfacePoint p0 = patches[f0.idx()].EvaluateWithDerivatives(bar0[1], bar0[2]);
      const SurfacePoint p1 = patches[f1.idx()].EvaluateWithDerivatives(bar1[1], bar1[2]);
      max_point = std::max(max_point, (p0.point - p1.point).norm());
      max_normal = std::max(max_normal, (p0.normal - p1.normal).norm());
    }
  }
  std::cout << name << ": " << edges << " interior edges x 50 points: max normal difference "
            << max_normal << " (flat faces: " << max_normal_jump_flat
            << "), max point difference " << max_point << "\n";
  EXPECT_GT(max_normal_jump_flat, 0.05);  // the mesh really is curved
  EXPECT_LT(max_normal, 1e-9);
  EXPECT_LT(max_point, 1e-12);
}

TEST(G1Patch, G1AcrossEdgesOfCurvedMesh) {
  StartGridOptions opt;
  opt.min = Eigen::Vector2d(-1, -1);
  opt.max = Eigen::Vector2d(1, 1);
  opt.spacing = 0.25;
  opt.height = [](double x, double y) { return 0.4 * std::sin(2 * x) * std::cos(1.5 * y) + 0.2 * x * y; };
  TinMesh mesh = MakeStartGrid(opt);
  // Irregular: jitter the points, then mean-of-face normals.
  std::mt19937 rng(3);
  std::normal_distribution<double> jitter(0.0, 0.03);
  for (auto v : mesh.vertices()) {
    auto p = mesh.point(v);
    mesh.set_point(v, p + TinMesh::Point(jitter(rng), jitter(rng), jitter(rng)));
  }
  UpdateVertexNormals(&mesh);
  CheckG1(mesh, "height field");
}

TEST(G1Patch, G1AcrossEdgesOfClosedMesh) {
  // Octahedron stretched to an ellipsoid (2 x 1 x 0.7): closed and strongly curved.
  TinMesh mesh;
  const double r[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<TinMesh::VertexHandle> v;
  for (auto& p : r) v.push_back(mesh.add_vertex(TinMesh::Point(2 * p[0], p[1], 0.7 * p[2])));
  const int f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                       {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (auto& t : f) mesh.add_face(v[t[0]], v[t[1]], v[t[2]]);
  UpdateVertexNormals(&mesh);
  CheckG1(mesh, "closed octahedron");
}

TEST(G1Patch, ApproximationOrderSphereAndCylinder) {
  for (int surface = 0; surface < 2; ++surface) {
    const char* name = surface == 0 ? "sphere" : "cylinder";
    std::vector<testing::SurfaceErrors> errors;
    std::vector<double> hs = {0.2, 0.1, 0.05, 0.025};
    for (double h : hs) {
      if (surface == 0) {
        errors.push_back(testing::MaxSurfaceError(
            testing::SphereCap(h), [](const Vector3d& p) { return p.norm() - 1.0; }));
      } else {
        errors.push_back(testing::MaxSurfaceError(testing::CylinderPatch(h), [](const Vector3d& p) {
          return testing::CylinderRadial(p).norm() - 1.0;
        }));
      }
    }
    for (size_t k = 0; k < hs.size(); ++k) {
      std::cout << name << " h=" << hs[k] << ": G1 max error " << errors[k].g1
                << ", flat max error " << errors[k].flat;
      if (k > 0) {
        const double rg = errors[k - 1].g1 / errors[k].g1;
        const double rf = errors[k - 1].flat / errors[k].flat;
        std::cout << "  ratios G1 " << rg << ", flat " << rf;
        EXPECT_GE(rg, 8.0) << name << " h=" << hs[k];
        EXPECT_GT(rf, 3.0);
        EXPECT_LT(rf, 5.0);
      }
      std::cout << "\n";
    }
  }
}

}  // namespace
}  // namespace facets
