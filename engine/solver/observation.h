// The linearised observation equation of one pixel (DESIGN.md section 4).
//
// Model. The pixel ray X0 + lambda * d hits the planar grey facet with corners P0, P1,
// P2 (tessellation points) at facet barycentrics (1-u-v, u, v). The facet lies in a
// geometry face whose vertices carry normals N0, N1, N2; the facet corners have face
// barycentrics C0, C1, C2. A normal displacement dn_i of the face's vertices moves
// every surface point by delta(t) * Nbar(t), with delta(t) = sum t_i dn_i and the
// pseudo-normal Nbar(t) = sum t_i N_i (linear interpolation, not normalised, seed 004
// eq. 5); t are face barycentrics. The ray then meets the moved surface at other facet
// coordinates, and the object grey value seen there, G(u, v) = sum G_j t~_j, is
// mapped into the image by the radiometric transfer:
//
//     predicted pixel grey value  p = (G - h0) / h1.
//
// The observation equation is  g + v = p(dn, dG, dh0, dh1)  linearised at the current
// values. Moving the surface by delta along Nbar slides the intersection point within
// the facet by  q = (Nbar.n / d.n) d - Nbar  per unit delta (n = facet normal), so
//     dp/d dn_i = t_i * grad_s G . q / h1,   dp/d G_j = t~_j / h1,
//     dp/d h0 = -1 / h1,                     dp/d h1 = -(G - h0) / h1^2.
// The finite-difference test checks every coefficient against PredictExact, the exact
// intersection of the ray with the displaced surface.
#pragma once

#include <Eigen/Core>
#include <array>

namespace facets {

// Everything about one ray and the facet it hit that the linearisation needs.
struct PixelRay {
  Eigen::Vector3d origin;     // projection centre X0
  Eigen::Vector3d direction;  // unit ray direction d
};

struct FacetState {
  std::array<Eigen::Vector3d, 3> corners;  // P0, P1, P2
  std::array<double, 3> grey;              // G at the corners (one channel)
  std::array<Eigen::Vector3d, 3> corner_face_barycentric;  // C0, C1, C2
  std::array<Eigen::Vector3d, 3> vertex_normals;           // N0, N1, N2 of the face
};

struct Radiometry {
  double h0 = 0.0;
  double h1 = 1.0;
};

struct ObservationCoefficients {
  double predicted = 0.0;         // p at the current values
  std::array<double, 3> dn{};     // dp / d dn_i, face vertices
  std::array<double, 3> grey{};   // dp / d G_j, facet corners
  double h0 = 0.0;                // dp / d h0
  double h1 = 0.0;                // dp / d h1
  double cos_incidence = 0.0;     // |d . n| / |n|
  bool valid = false;             // false at grazing incidence (degenerate geometry)
};

// Linearisation at the hit (u, v) of the ray in the facet.
ObservationCoefficients Linearise(const PixelRay& ray, const FacetState& facet, double u,
                                  double v, const Radiometry& radiometry);

// The exact predicted grey value after displacing the face vertices by dn along the
// pseudo-normal field and changing the grey values and radiometry, found by Newton
// iteration for the intersection of the ray with the displaced facet (starting at
// (u, v)). Reference for finite-difference tests; not used in the adjustment.
double PredictExact(const PixelRay& ray, const FacetState& facet, double u, double v,
                    const std::array<double, 3>& dn, const Radiometry& radiometry);

}  // namespace facets
