// Nielson's side-vertex G1 interpolant on one triangle (DESIGN.md section 3).
//
// Construction (all of it depends only on the three vertices X_i and unit normals N_i):
//
// Boundary curve between vertices a and b (EdgeCurve): the cubic Hermite curve
//   C(s), s in [0, 1], C(0) = X_a, C(1) = X_b, whose end tangents are the chord
//   X_b - X_a projected onto the tangent plane at each end and scaled back to the chord
//   length (so a flat configuration gives the straight segment, and a circular arc is
//   reproduced to fourth order). Reversing a and b gives the same curve reversed.
//   Normal field along it: m(s) = (1-s) N_a + s N_b made orthogonal to C'(s); it
//   interpolates N_a, N_b because the end tangents lie in the tangent planes.
//
// Side-vertex partial interpolant P_i for vertex i (opposite edge j -> k, with
//   j = i+1, k = i+2 mod 3): the point with barycentrics (b_i, b_j, b_k) lies on the
//   segment from vertex i to the edge point with edge parameter s = b_k / (b_j + b_k),
//   at parameter u = b_j + b_k = 1 - b_i. P_i is the cubic Hermite curve from X_i
//   to S = C_jk(s) evaluated at u; its end tangents are the chord S - X_i projected onto
//   the tangent plane at X_i (normal N_i) and onto the tangent plane at S given by the
//   edge's normal field m_jk(s), each scaled to the chord length. P_i reproduces all
//   three boundary curves (on edges ij and ik the side-vertex curve is the edge curve)
//   and its cross-boundary derivative on edge jk lies in the plane orthogonal to
//   m_jk(s).
//
// Blend: X = sum_i w_i P_i with w_i = (b_j b_k)^2 / sum over the three pairs. On edge jk
//   w_i = 1 and w_j, w_k vanish to second order, and since all P agree on the boundary,
//   sum_i dw_i P_i = 0 there: dX = dP_i. Hence the tangent plane along an edge is the
//   one given by the shared normal field m(s): neighbouring patches meet G1.
//
// Barycentrics: (b0, b1, b2) with b0 = 1 - b1 - b2 for vertex 0; the patch is evaluated
// as X(b1, b2). At a vertex (b_i = 1) the weights are 0/0: the vertex itself is
// returned, and the derivatives there are the two boundary-curve tangents.
//
// Evaluation allocates nothing; all per-triangle data is precomputed in the
// constructor (a few hundred bytes per patch).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

namespace facets {

// Cubic Hermite boundary curve with its normal field (see above).
class EdgeCurve {
 public:
  EdgeCurve() = default;
  // n_a, n_b need not be unit (they are normalised).
  EdgeCurve(const Eigen::Vector3d& x_a, const Eigen::Vector3d& n_a,
            const Eigen::Vector3d& x_b, const Eigen::Vector3d& n_b);

  // The straight chord from x_a to x_b, with the same normal field (a crease edge:
  // see mesh/creases.h).
  static EdgeCurve Straight(const Eigen::Vector3d& x_a, const Eigen::Vector3d& n_a,
                            const Eigen::Vector3d& x_b, const Eigen::Vector3d& n_b);

  Eigen::Vector3d Point(double s) const;
  // dC/ds.
  Eigen::Vector3d Tangent(double s) const;
  // Unit normal field m(s)/|m(s)|: the surface normal of the G1 surface along the edge.
  Eigen::Vector3d Normal(double s) const;

  // Cubic coefficients: C(s) = c[0] + c[1] s + c[2] s^2 + c[3] s^3.
  const std::array<Eigen::Vector3d, 4>& coefficients() const { return c_; }

 private:
  std::array<Eigen::Vector3d, 4> c_;
  Eigen::Vector3d n_a_ = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d n_b_ = Eigen::Vector3d::UnitZ();
};

// Tangent at x_from of the curve toward x_to: the chord projected onto the plane
// orthogonal to unit normal n, scaled to the chord length (the chord itself when it is
// parallel to n).
Eigen::Vector3d HermiteEndTangent(const Eigen::Vector3d& x_from, const Eigen::Vector3d& x_to,
                                  const Eigen::Vector3d& n);

struct SurfacePoint {
  Eigen::Vector3d point;
  Eigen::Vector3d d_b1;    // dX/db1 (b2 fixed, b0 = 1 - b1 - b2)
  Eigen::Vector3d d_b2;    // dX/db2 (b1 fixed)
  Eigen::Vector3d normal;  // unit, (d_b1 x d_b2) normalised: the side of a CCW face
};

class G1Patch {
 public:
  G1Patch() = default;
  // Vertices in face order (counter-clockwise seen from the normals' side) and their
  // normals (normalised here).
  G1Patch(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
          const Eigen::Vector3d& n0, const Eigen::Vector3d& n1, const Eigen::Vector3d& n2);
  // As above, with straight boundary curves for the edges flagged (edge i opposite
  // vertex i). On edge i only the partial interpolant P_i has weight, and it ends on
  // the boundary curve, so the patch runs exactly along the chord there: neighbouring
  // patches meet continuously across a crease whatever their corner normals.
  G1Patch(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
          const Eigen::Vector3d& n0, const Eigen::Vector3d& n1, const Eigen::Vector3d& n2,
          const std::array<bool, 3>& straight_edges);

  // Surface point at barycentrics (1 - b1 - b2, b1, b2). Values slightly outside the
  // triangle evaluate the natural extension (used by closest-point searches).
  Eigen::Vector3d Evaluate(double b1, double b2) const;
  // Point, analytic first derivatives (forward-mode dual numbers) and unit normal.
  SurfacePoint EvaluateWithDerivatives(double b1, double b2) const;
  Eigen::Vector3d Normal(double b1, double b2) const {
    return EvaluateWithDerivatives(b1, b2).normal;
  }
  // Flat (linear) interpolation of the vertices, for comparison.
  Eigen::Vector3d EvaluateFlat(double b1, double b2) const {
    return (1.0 - b1 - b2) * x_[0] + b1 * x_[1] + b2 * x_[2];
  }

  const Eigen::Vector3d& vertex(int i) const { return x_[i]; }
  const Eigen::Vector3d& vertex_normal(int i) const { return n_[i]; }
  // Boundary curve opposite vertex i, running from vertex i+1 to vertex i+2 (mod 3).
  const EdgeCurve& edge(int i) const { return edge_[i]; }

  // Implementation detail, public for the templated evaluator in g1_patch.cc.
  template <typename T>
  void EvaluateT(const T& b1, const T& b2, T out[3]) const;

 private:
  std::array<Eigen::Vector3d, 3> x_;
  std::array<Eigen::Vector3d, 3> n_;
  std::array<EdgeCurve, 3> edge_;
};

}  // namespace facets
