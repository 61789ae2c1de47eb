// Shared helpers for the mesh/ tests: meshes on analytic surfaces with exact normals.
#pragma once

#include <cmath>
#include <functional>

#include "mesh/tin.h"

namespace facets::testing {

// A 1 m grid over [-half, half]^2 (in m) sampling the height function.
inline TinMesh GridMesh(double half, std::function<double(double, double)> height) {
  StartGridOptions grid;
  grid.min = Eigen::Vector2d(-half, -half);
  grid.max = Eigen::Vector2d(half, half);
  grid.spacing = 1.0;
  grid.height = std::move(height);
  return MakeStartGrid(grid);
}

// Unit sphere cap over [-0.5, 0.5]^2 (z = sqrt(1 - x^2 - y^2)) at grid spacing h,
// with the exact sphere normals.
inline TinMesh SphereCap(double h, double half = 0.5) {
  StartGridOptions opt;
  opt.min = Eigen::Vector2d(-half, -half);
  opt.max = Eigen::Vector2d(half, half);
  opt.spacing = h;
  opt.height = [](double x, double y) { return std::sqrt(1.0 - x * x - y * y); };
  TinMesh mesh = MakeStartGrid(opt);
  for (auto v : mesh.vertices()) mesh.set_normal(v, mesh.point(v).normalized());
  return mesh;
}

// Axis of the test cylinder: horizontal, rotated 30 degrees from X; radius 1.
inline Eigen::Vector3d CylinderAxis() {
  return Eigen::Vector3d(std::cos(M_PI / 6), std::sin(M_PI / 6), 0.0);
}
inline Eigen::Vector3d CylinderRadial(const Eigen::Vector3d& p) {
  const Eigen::Vector3d a = CylinderAxis();
  return p - p.dot(a) * a;
}
inline TinMesh CylinderPatch(double h, double half = 0.5) {
  StartGridOptions opt;
  opt.min = Eigen::Vector2d(-half, -half);
  opt.max = Eigen::Vector2d(half, half);
  opt.spacing = h;
  opt.height = [](double x, double y) {
    const Eigen::Vector3d a = CylinderAxis();
    const double d = -x * a.y() + y * a.x();
    return std::sqrt(1.0 - d * d);
  };
  TinMesh mesh = MakeStartGrid(opt);
  for (auto v : mesh.vertices()) {
    mesh.set_normal(v, ToOpenMesh(CylinderRadial(ToEigen(mesh.point(v))).normalized()));
  }
  return mesh;
}

// Max over faces and a barycentric lattice (step 1/n) of dist(point) for the G1
// surface and for the flat triangles.
struct SurfaceErrors {
  double g1 = 0.0;
  double flat = 0.0;
};
inline SurfaceErrors MaxSurfaceError(const TinMesh& mesh,
                                     const std::function<double(const Eigen::Vector3d&)>& dist,
                                     int n = 8) {
  SurfaceErrors e;
  for (const G1Patch& patch : BuildPatches(mesh)) {
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i + j <= n; ++i) {
        const double b1 = static_cast<double>(i) / n, b2 = static_cast<double>(j) / n;
        e.g1 = std::max(e.g1, std::abs(dist(patch.Evaluate(b1, b2))));
        e.flat = std::max(e.flat, std::abs(dist(patch.EvaluateFlat(b1, b2))));
      }
    }
  }
  return e;
}

// Local index (0..2, fv_range order) of vertex v in face f, or -1.
inline int LocalIndex(const TinMesh& mesh, TinMesh::FaceHandle f, TinMesh::VertexHandle v) {
  int k = 0;
  for (auto w : mesh.fv_range(f)) {
    if (w == v) return k;
    ++k;
  }
  return -1;
}

}  // namespace facets::testing
