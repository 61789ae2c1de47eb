#include "engine/solver/observation.h"

#include <Eigen/Dense>
#include <cmath>

namespace facets {

ObservationCoefficients Linearise(const PixelRay& ray, const FacetState& facet, double u,
                                  double v, const Radiometry& radiometry) {
  ObservationCoefficients c;
  const Eigen::Vector3d e1 = facet.corners[1] - facet.corners[0];
  const Eigen::Vector3d e2 = facet.corners[2] - facet.corners[0];
  const Eigen::Vector3d n = e1.cross(e2);
  const double n2 = n.squaredNorm();
  const double d_dot_n = ray.direction.dot(n);
  if (n2 <= 0.0) return c;
  c.cos_incidence = std::abs(d_dot_n) / std::sqrt(n2);
  if (c.cos_incidence < 1e-6) return c;

  const double w0 = 1.0 - u - v;
  const Eigen::Vector3d t = w0 * facet.corner_face_barycentric[0] +
                            u * facet.corner_face_barycentric[1] +
                            v * facet.corner_face_barycentric[2];
  const Eigen::Vector3d pseudo_normal = t[0] * facet.vertex_normals[0] +
                                        t[1] * facet.vertex_normals[1] +
                                        t[2] * facet.vertex_normals[2];
  // Tangential slide of the hit point per unit displacement, in facet coordinates
  // (du, dv) via the dual basis of (e1, e2) in the facet plane.
  const Eigen::Vector3d q =
      (pseudo_normal.dot(n) / d_dot_n) * ray.direction - pseudo_normal;
  const double du = q.dot(e2.cross(n)) / n2;
  const double dv = q.dot(n.cross(e1)) / n2;
  const double grey = w0 * facet.grey[0] + u * facet.grey[1] + v * facet.grey[2];
  const double dgrey_ddelta =
      (facet.grey[1] - facet.grey[0]) * du + (facet.grey[2] - facet.grey[0]) * dv;

  const double inv_h1 = 1.0 / radiometry.h1;
  c.predicted = (grey - radiometry.h0) * inv_h1;
  for (int i = 0; i < 3; ++i) c.dn[i] = t[i] * dgrey_ddelta * inv_h1;
  c.grey = {w0 * inv_h1, u * inv_h1, v * inv_h1};
  c.h0 = -inv_h1;
  c.h1 = -(grey - radiometry.h0) * inv_h1 * inv_h1;
  c.valid = true;
  return c;
}

double PredictExact(const PixelRay& ray, const FacetState& facet, double u, double v,
                    const std::array<double, 3>& dn, const Radiometry& radiometry) {
  const auto& C = facet.corner_face_barycentric;
  const auto& N = facet.vertex_normals;
  const Eigen::Vector3d dn_vec(dn[0], dn[1], dn[2]);
  auto face_barycentric = [&](double uu, double vv) {
    return Eigen::Vector3d((1 - uu - vv) * C[0] + uu * C[1] + vv * C[2]);
  };
  auto pseudo_normal = [&](const Eigen::Vector3d& t) {
    return Eigen::Vector3d(t[0] * N[0] + t[1] * N[1] + t[2] * N[2]);
  };
  const Eigen::Vector3d e1 = facet.corners[1] - facet.corners[0];
  const Eigen::Vector3d e2 = facet.corners[2] - facet.corners[0];
  // Unknowns (u, v, lambda); F = P(u,v) + delta(u,v) Nbar(u,v) - X0 - lambda d = 0.
  Eigen::Vector3d x(u, v, (facet.corners[0] + u * e1 + v * e2 - ray.origin).dot(ray.direction));
  const Eigen::Vector3d dt_du = C[1] - C[0];
  const Eigen::Vector3d dt_dv = C[2] - C[0];
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Eigen::Vector3d t = face_barycentric(x[0], x[1]);
    const double delta = t.dot(dn_vec);
    const Eigen::Vector3d nbar = pseudo_normal(t);
    const Eigen::Vector3d f = facet.corners[0] + x[0] * e1 + x[1] * e2 + delta * nbar -
                              ray.origin - x[2] * ray.direction;
    Eigen::Matrix3d jacobian;
    jacobian.col(0) = e1 + dt_du.dot(dn_vec) * nbar + delta * pseudo_normal(dt_du);
    jacobian.col(1) = e2 + dt_dv.dot(dn_vec) * nbar + delta * pseudo_normal(dt_dv);
    jacobian.col(2) = -ray.direction;
    const Eigen::Vector3d step = jacobian.partialPivLu().solve(f);
    x -= step;
    if (step.norm() < 1e-15) break;
  }
  const double grey =
      (1 - x[0] - x[1]) * facet.grey[0] + x[0] * facet.grey[1] + x[1] * facet.grey[2];
  return (grey - radiometry.h0) / radiometry.h1;
}

}  // namespace facets
