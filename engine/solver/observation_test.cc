#include "engine/solver/observation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <iostream>
#include <random>

#include "mesh/tessellation.h"

namespace facets {
namespace {

// A facet of a geometry face cut from a sphere of radius 20 m (curved surface), with
// the exact sphere normals at the face vertices; the ray comes in obliquely.
struct Case {
  PixelRay ray;
  FacetState facet;
  double u, v;
};

Case MakeCase(std::mt19937& rng, int sub_triangle) {
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const double radius = 20.0;
  auto on_sphere = [&](double az, double el) -> Eigen::Vector3d {
    return Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                           std::sin(el)) * radius;
  };
  const double az = uni(rng) * 0.3, el = 0.6 + uni(rng) * 0.2;
  const std::array<Eigen::Vector3d, 3> vertices = {
      on_sphere(az, el), on_sphere(az + 0.15, el), on_sphere(az + 0.05, el + 0.12)};
  Case c;
  const auto& corners = SubTriangleCorners(sub_triangle);
  for (int j = 0; j < 3; ++j) {
    c.facet.vertex_normals[j] = vertices[j].normalized();
    c.facet.corner_face_barycentric[j] = corners[j];
    // Corners on the sphere (a curved surface: the facet is a chord plane).
    const Eigen::Vector3d flat = corners[j][0] * vertices[0] + corners[j][1] * vertices[1] +
                                 corners[j][2] * vertices[2];
    c.facet.corners[j] = flat.normalized() * radius;
    c.facet.grey[j] = 128.0 + 60.0 * uni(rng);
  }
  c.u = 0.2 + 0.2 * (uni(rng) + 1) / 2;
  c.v = 0.2 + 0.2 * (uni(rng) + 1) / 2;
  const Eigen::Vector3d hit = (1 - c.u - c.v) * c.facet.corners[0] + c.u * c.facet.corners[1] +
                              c.v * c.facet.corners[2];
  // Oblique: about 40-60 degrees off the surface normal.
  const Eigen::Vector3d normal = hit.normalized();
  Eigen::Vector3d side = normal.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d towards_camera = (normal + (1.0 + 0.3 * uni(rng)) * side).normalized();
  c.ray.origin = hit + 500.0 * towards_camera;
  c.ray.direction = -towards_camera;
  return c;
}

TEST(Observation, EveryCoefficientMatchesCentralDifferences) {
  std::mt19937 rng(11);
  const Radiometry radiometry{3.0, 1.1};
  double worst = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    const Case c = MakeCase(rng, trial % kSubTrianglesPerFace);
    const ObservationCoefficients lin = Linearise(c.ray, c.facet, c.u, c.v, radiometry);
    ASSERT_TRUE(lin.valid) << "cos " << lin.cos_incidence << " trial " << trial;
    const std::array<double, 3> zero{0, 0, 0};
    EXPECT_NEAR(lin.predicted, PredictExact(c.ray, c.facet, c.u, c.v, zero, radiometry), 1e-9);
    auto check = [&](double analytic, double numeric) {
      const double scale = std::max(std::abs(numeric), 1e-3);
      worst = std::max(worst, std::abs(analytic - numeric) / scale);
      EXPECT_NEAR(analytic, numeric, 1e-4 * scale);
    };
    const double h = 1e-5;
    for (int i = 0; i < 3; ++i) {
      std::array<double, 3> plus = zero, minus = zero;
      plus[i] = h;
      minus[i] = -h;
      check(lin.dn[i], (PredictExact(c.ray, c.facet, c.u, c.v, plus, radiometry) -
                        PredictExact(c.ray, c.facet, c.u, c.v, minus, radiometry)) / (2 * h));
      FacetState g_plus = c.facet, g_minus = c.facet;
      g_plus.grey[i] += h;
      g_minus.grey[i] -= h;
      check(lin.grey[i], (PredictExact(c.ray, g_plus, c.u, c.v, zero, radiometry) -
                          PredictExact(c.ray, g_minus, c.u, c.v, zero, radiometry)) / (2 * h));
    }
    Radiometry plus = radiometry, minus = radiometry;
    plus.h0 += h;
    minus.h0 -= h;
    check(lin.h0, (PredictExact(c.ray, c.facet, c.u, c.v, zero, plus) -
                   PredictExact(c.ray, c.facet, c.u, c.v, zero, minus)) / (2 * h));
    plus = radiometry;
    minus = radiometry;
    plus.h1 += h;
    minus.h1 -= h;
    check(lin.h1, (PredictExact(c.ray, c.facet, c.u, c.v, zero, plus) -
                   PredictExact(c.ray, c.facet, c.u, c.v, zero, minus)) / (2 * h));
  }
  std::cout << "worst relative deviation analytic vs central difference: " << worst << "\n";
}

TEST(Observation, GrazingRayIsNoObservation) {
  std::mt19937 rng(3);
  Case c = MakeCase(rng, 0);
  const Eigen::Vector3d n = (c.facet.corners[1] - c.facet.corners[0])
                                .cross(c.facet.corners[2] - c.facet.corners[0])
                                .normalized();
  c.ray.direction = (c.facet.corners[1] - c.facet.corners[0]).normalized();
  c.ray.direction -= c.ray.direction.dot(n) * n;
  c.ray.direction.normalize();
  EXPECT_FALSE(Linearise(c.ray, c.facet, c.u, c.v, Radiometry{}).valid);
}

}  // namespace
}  // namespace facets
