#include "mesh/local_ops.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "mesh/test_util.h"

namespace facets {
namespace {

using Eigen::Vector3d;

// Minimum dot product of each face normal with its vertices' normals (< 0: fold-over).
double MinFaceVertexNormalDot(const TinMesh& mesh) {
  double m = 1.0;
  for (auto f : mesh.faces()) {
    const auto nf = mesh.calc_face_normal(f);
    for (auto v : mesh.fv_range(f)) m = std::min(m, nf | mesh.normal(v));
  }
  return m;
}

TEST(LocalOps, FlipMakesBadQuadDelaunay) {
  // A tilted plane quad (a, b, c, d) with a long diagonal a-b: not Delaunay in the tangent
  // plane although it would be in XY after the tilt... the criterion uses the tangent plane.
  const Vector3d n = Vector3d(0, -0.8, 0.6);  // plane tilted steeply about X
  const Vector3d e1(1, 0, 0), e2 = n.cross(e1);
  TinMesh mesh;
  auto add = [&](double x, double y) {
    const Vector3d p = x * e1 + y * e2;
    auto v = mesh.add_vertex(ToOpenMesh(p));
    mesh.set_normal(v, ToOpenMesh(n));
    return v;
  };
  const auto a = add(-1, 0), b = add(1, 0), c = add(0, 0.2), d = add(0, -0.2);
  mesh.add_face(a, b, c);
  mesh.add_face(b, a, d);
  const auto e = mesh.edge_handle(mesh.find_halfedge(a, b));
  EXPECT_FALSE(IsTangentDelaunay(mesh, e));
  EXPECT_TRUE(CanFlip(mesh, e));
  EXPECT_EQ(MakeTangentDelaunay(&mesh), 1);
  EXPECT_TRUE(mesh.find_halfedge(c, d).is_valid());
  for (auto ed : mesh.edges()) EXPECT_TRUE(IsTangentDelaunay(mesh, ed));
  for (auto f : mesh.faces()) EXPECT_GT(mesh.calc_face_normal(f) | ToOpenMesh(n), 0.99);
}

TEST(LocalOps, NonConvexQuadIsNotFlipped) {
  TinMesh mesh;
  auto add = [&](double x, double y) {
    auto v = mesh.add_vertex(TinMesh::Point(x, y, 0));
    mesh.set_normal(v, TinMesh::Normal(0, 0, 1));
    return v;
  };
  // Quad a-d-b-c is non-convex at d (d lies beyond the line c-... ): flipping would fold.
  const auto a = add(0, 0), b = add(1, 0), c = add(0.5, 0.1), d = add(1.5, -0.05);
  mesh.add_face(a, b, c);
  mesh.add_face(b, a, d);
  const auto e = mesh.edge_handle(mesh.find_halfedge(a, b));
  EXPECT_FALSE(CanFlip(mesh, e));
  EXPECT_EQ(MakeTangentDelaunay(&mesh), 0);
}

TinMesh JitteredPlane(double tilt, unsigned seed) {
  StartGridOptions opt;
  opt.spacing = 0.1;
  opt.height = [tilt](double x, double y) { return tilt * x - 0.3 * y + 2.0; };
  TinMesh mesh = MakeStartGrid(opt);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.035, 0.035);
  for (auto v : mesh.vertices()) {
    if (mesh.is_boundary(v)) continue;
    const double x = mesh.point(v)[0] + u(rng), y = mesh.point(v)[1] + u(rng);
    mesh.set_point(v, TinMesh::Point(x, y, tilt * x - 0.3 * y + 2.0));
  }
  UpdateVertexNormals(&mesh);
  return mesh;
}

TEST(LocalOps, DelaunayAfterFlipsOnJitteredGrid) {
  TinMesh mesh = JitteredPlane(0.7, 1);
  int bad = 0;
  for (auto e : mesh.edges()) bad += !IsTangentDelaunay(mesh, e);
  const int flips = MakeTangentDelaunay(&mesh);
  int bad_after = 0;
  for (auto e : mesh.edges()) bad_after += !IsTangentDelaunay(mesh, e);
  std::cout << "jittered grid: " << bad << " non-Delaunay edges, " << flips << " flips, "
            << bad_after << " left\n";
  EXPECT_GT(bad, 0);
  EXPECT_EQ(bad_after, 0);
  EXPECT_GT(MinFaceVertexNormalDot(mesh), 0.99);
}

TEST(LocalOps, SmoothingKeepsPlane) {
  TinMesh mesh = JitteredPlane(0.7, 2);
  const AngleStats before = FaceAngleStats(mesh);
  SmoothingOptions opt;
  opt.iterations = 5;
  const SmoothingReport rep = TangentialSmooth(&mesh, opt);
  const AngleStats after = FaceAngleStats(mesh);
  double max_dev = 0;
  for (auto v : mesh.vertices()) {
    const auto p = mesh.point(v);
    max_dev = std::max(max_dev, std::abs(p[2] - (0.7 * p[0] - 0.3 * p[1] + 2.0)));
  }
  std::cout << "plane smoothing: moves " << rep.moved << " (off surface " << rep.off_surface
            << "), max distance to plane " << max_dev << ", min angle "
            << before.min_angle * 180 / M_PI << " -> " << after.min_angle * 180 / M_PI
            << " deg, mean min angle " << before.mean_min_angle * 180 / M_PI << " -> "
            << after.mean_min_angle * 180 / M_PI << "\n";
  EXPECT_LT(max_dev, 1e-12);
  EXPECT_GT(after.mean_min_angle, before.mean_min_angle);
  EXPECT_GT(MinFaceVertexNormalDot(mesh), 0.99);
}

TEST(LocalOps, SmoothingKeepsSphere) {
  TinMesh mesh = testing::SphereCap(0.1);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.03, 0.03);
  for (auto v : mesh.vertices()) {
    if (mesh.is_boundary(v)) continue;
    const auto p = mesh.point(v) + TinMesh::Point(u(rng), u(rng), 0);
    mesh.set_point(v, p.normalized());
    mesh.set_normal(v, p.normalized());
  }
  const auto sphere = [](const Vector3d& p) { return p.norm() - 1.0; };
  const double g1_error = testing::MaxSurfaceError(mesh, sphere).g1;
  const AngleStats before = FaceAngleStats(mesh);
  SmoothingOptions opt;
  opt.iterations = 3;
  TangentialSmooth(&mesh, opt);
  double max_dev = 0;
  for (auto v : mesh.vertices()) max_dev = std::max(max_dev, std::abs(mesh.point(v).norm() - 1));
  const AngleStats after = FaceAngleStats(mesh);
  std::cout << "sphere smoothing: G1 error before " << g1_error
            << ", max vertex distance to sphere after 3 iterations " << max_dev
            << ", mean min angle " << before.mean_min_angle * 180 / M_PI << " -> "
            << after.mean_min_angle * 180 / M_PI << " deg\n";
  // Vertices slide on the G1 surface: off the sphere by at most its error (x iterations).
  EXPECT_LT(max_dev, 3 * g1_error);
  EXPECT_GT(after.mean_min_angle, before.mean_min_angle);
}

// A gable roof (ridge along x at y = 0.5, slopes 0.6) on a jittered grid: plain G1
// smoothing slides the vertices next to the ridge over the rounded G1 surface, off the
// roof planes; smoothing on the creased surface keeps every vertex on its plane.
TEST(LocalOps, SmoothingOnCreasedSurfaceKeepsTheRidgeSharp) {
  auto gable = [](double x, double y) {
    (void)x;
    return 2.0 - 0.6 * std::abs(y - 0.5);
  };
  auto make = [&]() {
    StartGridOptions opt;
    opt.spacing = 0.1;
    opt.height = gable;
    TinMesh mesh = MakeStartGrid(opt);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-0.035, 0.035);
    for (auto v : mesh.vertices()) {
      if (mesh.is_boundary(v)) continue;
      const double y0 = mesh.point(v)[1];
      const double x = mesh.point(v)[0] + u(rng);
      const double y = std::abs(y0 - 0.5) < 1e-9 ? y0 : y0 + u(rng);  // ridge vertices stay on it
      mesh.set_point(v, TinMesh::Point(x, y, gable(x, y)));
    }
    UpdateVertexNormals(&mesh);
    return mesh;
  };
  auto max_deviation = [&](const TinMesh& mesh) {
    double m = 0.0;
    for (auto v : mesh.vertices()) {
      const auto p = mesh.point(v);
      m = std::max(m, std::abs(p[2] - gable(p[0], p[1])));
    }
    return m;
  };
  SmoothingOptions opt;
  opt.iterations = 3;
  TinMesh plain = make();
  TangentialSmooth(&plain, opt);
  TinMesh creased = make();
  const AngleStats before = FaceAngleStats(creased);
  opt.crease_angle_deg = 20.0;
  const SmoothingReport rep = TangentialSmooth(&creased, opt);
  const AngleStats after = FaceAngleStats(creased);
  std::cout << "gable smoothing: max distance to the roof planes, plain G1 " << max_deviation(plain)
            << " m, creased " << max_deviation(creased) << " m; " << rep.crease_vertices
            << " crease vertices held; mean min angle " << before.mean_min_angle * 180 / M_PI << " -> "
            << after.mean_min_angle * 180 / M_PI << " deg\n";
  EXPECT_GT(max_deviation(plain), 1e-3);
  EXPECT_LT(max_deviation(creased), 1e-9);
  EXPECT_EQ(rep.crease_vertices, 11);  // the ridge: x = 0, 0.1, .., 1
  EXPECT_GT(after.mean_min_angle, before.mean_min_angle);
}

TEST(LocalOps, SplitEdgeOnG1Surface) {
  TinMesh mesh = testing::SphereCap(0.25);
  const size_t nv = mesh.n_vertices(), nf = mesh.n_faces();
  const auto e = mesh.edge_handle(40);
  const EdgeCurve curve = MakeEdgeCurve(mesh, e);
  const bool boundary = mesh.is_boundary(e);
  const auto v = SplitEdge(&mesh, e);
  EXPECT_EQ(mesh.n_vertices(), nv + 1);
  EXPECT_EQ(mesh.n_faces(), nf + (boundary ? 1 : 2));
  EXPECT_LT((ToEigen(mesh.point(v)) - curve.Point(0.5)).norm(), 1e-15);
  std::cout << "split vertex distance to sphere: " << std::abs(mesh.point(v).norm() - 1) << "\n";
  EXPECT_LT(std::abs(mesh.point(v).norm() - 1), 1e-4);
}

TEST(LocalOps, RemoveVertex) {
  TinMesh mesh = JitteredPlane(0.2, 3);
  MakeTangentDelaunay(&mesh);
  const size_t nv = mesh.n_vertices(), nf = mesh.n_faces();
  TinMesh::VertexHandle inner;
  for (auto v : mesh.vertices()) {
    if (!mesh.is_boundary(v)) {
      inner = v;
      break;
    }
  }
  ASSERT_TRUE(RemoveVertex(&mesh, inner));
  EXPECT_EQ(mesh.n_vertices(), nv - 1);
  EXPECT_EQ(mesh.n_faces(), nf - 2);
  EXPECT_GT(MinFaceVertexNormalDot(mesh), 0.99);
  for (auto e : mesh.edges()) EXPECT_TRUE(IsTangentDelaunay(mesh, e, 1e-6) || !CanFlip(mesh, e));
}

// A 2.5D start whose middle strip stood up into a 3 m wall: x in [0.4, 0.5] rises from
// 0 to 3. The wall's triangles are stretched 30x vertically.
TinMesh StoodUpWall() {
  StartGridOptions opt;
  opt.min = Eigen::Vector2d(0, 0);
  opt.max = Eigen::Vector2d(1, 1);
  opt.spacing = 0.1;
  opt.height = [](double x, double) { return x < 0.45 ? 0.0 : 3.0; };
  return MakeStartGrid(opt);
}

TEST(LocalOps, QualityPassSplitsWall) {
  TinMesh mesh = StoodUpWall();
  double max_before = 0;
  for (auto e : mesh.edges()) max_before = std::max(max_before, mesh.calc_edge_length(e));
  QualityOptions q;
  q.target_edge_length = 0.1 * std::sqrt(2.0);
  const size_t nv = mesh.n_vertices();
  const QualityReport rep = QualityPass(&mesh, q);
  std::cout << "wall: max edge " << max_before << " -> " << rep.max_edge_length << " (limit "
            << q.split_factor * q.target_edge_length << "), " << rep.splits << " splits, "
            << rep.flips << " flips, vertices " << nv << " -> " << mesh.n_vertices()
            << ", min face-vertex normal dot " << MinFaceVertexNormalDot(mesh) << "\n";
  EXPECT_GT(rep.splits, 0);
  EXPECT_LE(rep.max_edge_length, q.split_factor * q.target_edge_length);
  EXPECT_EQ(static_cast<int>(mesh.n_vertices() - nv), rep.splits);
  // No fold-overs: every face agrees with its vertices' normals.
  EXPECT_GT(MinFaceVertexNormalDot(mesh), 0.0);
  int bad = 0;
  for (auto e : mesh.edges()) bad += !IsTangentDelaunay(mesh, e) && CanFlip(mesh, e);
  EXPECT_EQ(bad, 0);
}

TEST(LocalOps, QualityPassNearSplitsOnlyThereAndSaysWhatChanged) {
  // The same wall, 1 m long in y; only the vertices with y < 0.35 are flagged: the wall's
  // stretched edges there are split and flipped, those beyond keep their length, and
  // VerticesChangedFrom names every vertex of a face the pass made or changed.
  TinMesh mesh = StoodUpWall();
  const TinMesh before = mesh;
  std::vector<bool> near(mesh.n_vertices(), false);
  for (auto v : mesh.vertices()) near[v.idx()] = mesh.point(v)[1] < 0.35;
  QualityOptions q;
  q.target_edge_length = 0.1 * std::sqrt(2.0);
  q.near = &near;
  const int long_near = CountLongEdges(mesh, q);
  const QualityReport rep = QualityPass(&mesh, q);
  EXPECT_GT(rep.splits, 0);
  EXPECT_GE(rep.splits, long_near);
  int long_far = 0, long_far_before = 0;
  const double limit = q.split_factor * q.target_edge_length;
  auto far = [](const TinMesh& m, TinMesh::EdgeHandle e) {
    const auto h = m.halfedge_handle(e, 0);
    return m.point(m.from_vertex_handle(h))[1] > 0.55 && m.point(m.to_vertex_handle(h))[1] > 0.55;
  };
  for (auto e : before.edges()) long_far_before += far(before, e) && before.calc_edge_length(e) > limit;
  for (auto e : mesh.edges()) long_far += far(mesh, e) && mesh.calc_edge_length(e) > limit;
  EXPECT_GT(long_far_before, 0);
  EXPECT_EQ(long_far, long_far_before);
  EXPECT_GT(MinFaceVertexNormalDot(mesh), 0.0);
  const std::vector<bool> changed = VerticesChangedFrom(mesh, before);
  int changed_far = 0;
  for (auto v : mesh.vertices()) {
    if (v.idx() >= static_cast<int>(before.n_vertices())) {
      EXPECT_TRUE(changed[v.idx()]);
    }
    changed_far += changed[v.idx()] && mesh.point(v)[1] > 0.65;
  }
  EXPECT_EQ(changed_far, 0);
  for (auto f : mesh.faces()) {
    std::vector<int> now, was;
    for (auto v : mesh.fv_range(f)) now.push_back(v.idx());
    if (f.idx() < static_cast<int>(before.n_faces())) {
      for (auto v : before.fv_range(before.face_handle(f.idx()))) was.push_back(v.idx());
    }
    if (now == was) continue;
    for (int v : now) EXPECT_TRUE(changed[v]) << "face " << f.idx();
  }
  EXPECT_EQ(VerticesChangedFrom(before, before), std::vector<bool>(before.n_vertices(), false));
}

// A 3 x 3 grid of 1 m, each cell cut by its diagonal from (i, j) to (i + 1, j + 1),
// counter-clockwise from +Z, with its middle vertex (1, 1) at `middle`.
TinMesh GridWithMiddleAt(const Vector3d& middle) {
  TinMesh mesh;
  std::vector<TinMesh::VertexHandle> v;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) v.push_back(mesh.add_vertex(ToOpenMesh(i == 1 && j == 1 ? middle : Vector3d(i, j, 0))));
  }
  for (int j = 0; j < 2; ++j) {
    for (int i = 0; i < 2; ++i) {
      const int a = 3 * j + i;
      mesh.add_face(v[a], v[a + 1], v[a + 4]);
      mesh.add_face(v[a], v[a + 4], v[a + 3]);
    }
  }
  UpdateVertexNormals(&mesh);
  return mesh;
}

double SmallestHeightRatio(const TinMesh& mesh) {
  double least = 1e300;
  for (auto f : mesh.faces()) {
    std::vector<Vector3d> p;
    for (auto v : mesh.fv_range(f)) p.push_back(ToEigen(mesh.point(v)));
    const double longest = std::max({(p[1] - p[0]).norm(), (p[2] - p[1]).norm(), (p[0] - p[2]).norm()});
    least = std::min(least, (p[1] - p[0]).cross(p[2] - p[0]).norm() / (longest * longest));
  }
  return least;
}

TEST(LocalOps, RepairFlipsAnInnerCap) {
  // The middle vertex on the segment between its ring neighbours (1, 0) and (2, 1): the
  // triangle of the three has no area; the triangle across that edge, with (2, 0), does.
  TinMesh mesh = GridWithMiddleAt(Vector3d(1.5, 0.5, 0));
  ASSERT_EQ(mesh.n_faces(), 8u);
  const DegenerateRepairReport r = RepairDegenerateTriangles(&mesh);
  EXPECT_EQ(r.degenerate, 1);
  EXPECT_EQ(r.flipped, 1);
  EXPECT_EQ(r.collapsed, 0);
  EXPECT_EQ(r.left, 0);
  EXPECT_EQ(mesh.n_faces(), 8u);
  EXPECT_GT(SmallestHeightRatio(mesh), 0.1);
}

TEST(LocalOps, RepairCollapsesANeedleAndABoundaryCap) {
  // The middle vertex on top of (1, 0): two needles (its edge to (1, 0) has no length).
  TinMesh needle = GridWithMiddleAt(Vector3d(1, 0, 0));
  const DegenerateRepairReport n = RepairDegenerateTriangles(&needle);
  EXPECT_EQ(n.degenerate, 2);
  EXPECT_EQ(n.left, 0);
  EXPECT_EQ(n.collapsed, 1);
  EXPECT_EQ(needle.n_vertices(), 8u);
  EXPECT_EQ(needle.n_faces(), 6u);
  EXPECT_GT(SmallestHeightRatio(needle), 0.1);
  for (auto v : needle.vertices()) EXPECT_TRUE(needle.normal(v).norm() > 0.99);
  // On the boundary edge from (0, 0) to (1, 0), halfway: a cap whose long edge has no
  // triangle across; the vertex goes into an end of that edge.
  TinMesh cap = GridWithMiddleAt(Vector3d(0.5, 0, 0));
  const DegenerateRepairReport c = RepairDegenerateTriangles(&cap);
  EXPECT_EQ(c.degenerate, 1);
  EXPECT_EQ(c.left, 0);
  EXPECT_EQ(c.collapsed, 1);
  EXPECT_EQ(cap.n_vertices(), 8u);
  EXPECT_GT(SmallestHeightRatio(cap), 0.1);
  // A sound mesh is left alone.
  TinMesh sound = GridWithMiddleAt(Vector3d(1, 1, 0.2));
  const DegenerateRepairReport s = RepairDegenerateTriangles(&sound);
  EXPECT_EQ(s.degenerate, 0);
  EXPECT_EQ(sound.n_vertices(), 9u);
}

}  // namespace
}  // namespace facets
