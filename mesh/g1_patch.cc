#include "mesh/g1_patch.h"

#include <algorithm>
#include <cmath>

namespace facets {
namespace {

// Forward-mode dual number with the two partial derivatives d/db1 and d/db2.
struct Jet {
  double v = 0.0, d1 = 0.0, d2 = 0.0;
  Jet() = default;
  Jet(double value) : v(value) {}  // NOLINT: constants promote implicitly
  Jet(double value, double p1, double p2) : v(value), d1(p1), d2(p2) {}
};
inline Jet operator+(const Jet& a, const Jet& b) { return {a.v + b.v, a.d1 + b.d1, a.d2 + b.d2}; }
inline Jet operator-(const Jet& a, const Jet& b) { return {a.v - b.v, a.d1 - b.d1, a.d2 - b.d2}; }
inline Jet operator-(const Jet& a) { return {-a.v, -a.d1, -a.d2}; }
inline Jet operator*(const Jet& a, const Jet& b) {
  return {a.v * b.v, a.d1 * b.v + a.v * b.d1, a.d2 * b.v + a.v * b.d2};
}
inline Jet operator*(double a, const Jet& b) { return {a * b.v, a * b.d1, a * b.d2}; }
inline Jet operator*(const Jet& a, double b) { return {a.v * b, a.d1 * b, a.d2 * b}; }
inline Jet operator/(const Jet& a, const Jet& b) {
  const double inv = 1.0 / b.v;
  const double q = a.v * inv;
  return {q, (a.d1 - q * b.d1) * inv, (a.d2 - q * b.d2) * inv};
}
inline Jet sqrt(const Jet& a) {
  const double r = std::sqrt(a.v);
  const double h = r > 0.0 ? 0.5 / r : 0.0;
  return {r, a.d1 * h, a.d2 * h};
}
inline double Val(const Jet& a) { return a.v; }
inline double Val(double a) { return a; }

// Minimal 3-vector over a scalar type (Eigen with a custom scalar would be slower).
template <typename T>
struct V3 {
  T x, y, z;
};
template <typename T>
inline V3<T> operator+(const V3<T>& a, const V3<T>& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <typename T>
inline V3<T> operator-(const V3<T>& a, const V3<T>& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <typename T>
inline V3<T> operator*(const T& s, const V3<T>& a) { return {s * a.x, s * a.y, s * a.z}; }
inline V3<Jet> operator*(double s, const V3<Jet>& a) { return {s * a.x, s * a.y, s * a.z}; }
template <typename T>
inline T Dot(const V3<T>& a, const V3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename T>
inline V3<T> Lift(const Eigen::Vector3d& a) { return {T(a.x()), T(a.y()), T(a.z())}; }
// Mixed: constant vector times scalar.
template <typename T>
inline V3<T> Scale(const Eigen::Vector3d& a, const T& s) { return {a.x() * s, a.y() * s, a.z() * s}; }

// Scales the projection q of chord d to the chord length; falls back to the chord when
// the projection degenerates (chord parallel to the normal).
template <typename T>
inline V3<T> ScaleToChord(const V3<T>& q, const V3<T>& d) {
  const T qq = Dot(q, q);
  const T dd = Dot(d, d);
  if (!(Val(qq) > 1e-24 * Val(dd))) return d;
  using std::sqrt;
  return sqrt(dd / qq) * q;
}

// Hermite coefficients (c0..c3) from ends and end tangents.
std::array<Eigen::Vector3d, 4> HermiteCoefficients(const Eigen::Vector3d& p0,
                                                   const Eigen::Vector3d& t0,
                                                   const Eigen::Vector3d& p1,
                                                   const Eigen::Vector3d& t1) {
  return {p0, t0, -3.0 * p0 - 2.0 * t0 + 3.0 * p1 - t1, 2.0 * p0 + t0 - 2.0 * p1 + t1};
}

// Below this sum of squared barycentric products the point is a vertex (0/0 weights).
constexpr double kCornerEps = 1e-200;

// At a corner, or within rounding of it (the two other barycentrics below 1e-12 in
// magnitude, possibly of opposite signs a hair outside the triangle): the blend's
// weights and derivatives are 0/0 or rounding noise there.
bool AtCorner(double b0, double b1, double b2) {
  const double q0 = b1 * b2, q1 = b2 * b0, q2 = b0 * b1;
  if (q0 * q0 + q1 * q1 + q2 * q2 < kCornerEps) return true;
  const double a0 = std::abs(b0), a1 = std::abs(b1), a2 = std::abs(b2);
  const double middle = std::max(std::min(a0, a1), std::min(std::max(a0, a1), a2));
  return middle < 1e-12;
}

int CornerIndex(double b0, double b1, double b2) {
  if (b1 >= b0 && b1 >= b2) return 1;
  if (b2 >= b0 && b2 >= b1) return 2;
  return 0;
}

}  // namespace

Eigen::Vector3d HermiteEndTangent(const Eigen::Vector3d& x_from, const Eigen::Vector3d& x_to,
                                  const Eigen::Vector3d& n) {
  const Eigen::Vector3d d = x_to - x_from;
  const Eigen::Vector3d q = d - d.dot(n) * n;
  const double qq = q.squaredNorm(), dd = d.squaredNorm();
  if (!(qq > 1e-24 * dd)) return d;
  return std::sqrt(dd / qq) * q;
}

EdgeCurve::EdgeCurve(const Eigen::Vector3d& x_a, const Eigen::Vector3d& n_a,
                     const Eigen::Vector3d& x_b, const Eigen::Vector3d& n_b)
    : n_a_(n_a.normalized()), n_b_(n_b.normalized()) {
  // End tangent at b is the derivative at s = 1: the chord a->b projected at b, which
  // is minus the tangent at b toward a; so reversing a and b reverses the curve.
  const Eigen::Vector3d t_a = HermiteEndTangent(x_a, x_b, n_a_);
  const Eigen::Vector3d t_b = -HermiteEndTangent(x_b, x_a, n_b_);
  c_ = HermiteCoefficients(x_a, t_a, x_b, t_b);
}

EdgeCurve EdgeCurve::Straight(const Eigen::Vector3d& x_a, const Eigen::Vector3d& n_a,
                              const Eigen::Vector3d& x_b, const Eigen::Vector3d& n_b) {
  EdgeCurve curve;
  curve.n_a_ = n_a.normalized();
  curve.n_b_ = n_b.normalized();
  curve.c_ = {x_a, x_b - x_a, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  return curve;
}

Eigen::Vector3d EdgeCurve::Point(double s) const {
  return c_[0] + s * (c_[1] + s * (c_[2] + s * c_[3]));
}

Eigen::Vector3d EdgeCurve::Tangent(double s) const {
  return c_[1] + s * (2.0 * c_[2] + s * 3.0 * c_[3]);
}

Eigen::Vector3d EdgeCurve::Normal(double s) const {
  const Eigen::Vector3d t = Tangent(s);
  const Eigen::Vector3d n = (1.0 - s) * n_a_ + s * n_b_;
  return (n - n.dot(t) / t.squaredNorm() * t).normalized();
}

G1Patch::G1Patch(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                 const Eigen::Vector3d& n0, const Eigen::Vector3d& n1, const Eigen::Vector3d& n2)
    : x_{x0, x1, x2}, n_{n0.normalized(), n1.normalized(), n2.normalized()} {
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    edge_[i] = EdgeCurve(x_[j], n_[j], x_[k], n_[k]);
  }
}

G1Patch::G1Patch(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                 const Eigen::Vector3d& n0, const Eigen::Vector3d& n1, const Eigen::Vector3d& n2,
                 const std::array<bool, 3>& straight_edges)
    : G1Patch(x0, x1, x2, n0, n1, n2) {
  for (int i = 0; i < 3; ++i) {
    if (!straight_edges[i]) continue;
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    edge_[i] = EdgeCurve::Straight(x_[j], n_[j], x_[k], n_[k]);
  }
}

template <typename T>
void G1Patch::EvaluateT(const T& b1, const T& b2, T out[3]) const {
  const T b[3] = {T(1.0) - b1 - b2, b1, b2};
  const T q0 = b[1] * b[2], q1 = b[2] * b[0], q2 = b[0] * b[1];
  const T wq[3] = {q0 * q0, q1 * q1, q2 * q2};
  const T denom = wq[0] + wq[1] + wq[2];
  V3<T> sum{T(0.0), T(0.0), T(0.0)};
  for (int i = 0; i < 3; ++i) {
    if (Val(wq[i]) == 0.0 && Val(denom) > 0.0) {
      // Weight zero to second order here: the partial interpolant does not matter.
      // (Its derivative contribution w' * P is zero too since w' = 0 where w = 0.)
      continue;
    }
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const T u = b[j] + b[k];
    if (std::abs(Val(u)) <= 1e-9 * (std::abs(Val(b[j])) + std::abs(Val(b[k])))) {
      // On the line b_j = -b_k through vertex i (a hair outside the triangle next to
      // it: b_i = 1, b_j = -b_k ~ 1e-16 after rounding) s = b_k / u is 0/0; P_i is X_i
      // there whatever s, and its weight (b_j b_k)^2 is negligible against the others.
      sum = sum + wq[i] * Lift<T>(x_[i]);
      continue;
    }
    const T s = b[k] / u;
    const auto& c = edge_[i].coefficients();
    // Boundary point S = C(s), tangent C'(s), normal field m(s).
    const V3<T> S = Lift<T>(c[0]) +
                    Scale(c[1], s) + Scale(c[2], s * s) + Scale(c[3], s * s * s);
    const V3<T> dS = Lift<T>(c[1]) + Scale(c[2], 2.0 * s) + Scale(c[3], 3.0 * s * s);
    const V3<T> nl = Scale(n_[j], T(1.0) - s) + Scale(n_[k], s);
    const V3<T> m = nl - (Dot(nl, dS) / Dot(dS, dS)) * dS;
    // Side-vertex curve from X_i to S.
    const V3<T> xi = Lift<T>(x_[i]);
    const V3<T> d = S - xi;
    const V3<T> ni = Lift<T>(n_[i]);
    const V3<T> t_i = ScaleToChord(d - Dot(d, ni) * ni, d);
    const V3<T> t_s = ScaleToChord(d - (Dot(d, m) / Dot(m, m)) * m, d);
    const T u2 = u * u, u3 = u2 * u;
    const T h00 = 2.0 * u3 - 3.0 * u2 + T(1.0);
    const T h10 = u3 - 2.0 * u2 + u;
    const T h01 = 3.0 * u2 - 2.0 * u3;
    const T h11 = u3 - u2;
    const V3<T> p = h00 * xi + h10 * t_i + h01 * S + h11 * t_s;
    sum = sum + wq[i] * p;
  }
  out[0] = sum.x / denom;
  out[1] = sum.y / denom;
  out[2] = sum.z / denom;
}

Eigen::Vector3d G1Patch::Evaluate(double b1, double b2) const {
  const double b0 = 1.0 - b1 - b2;
  if (AtCorner(b0, b1, b2)) return x_[CornerIndex(b0, b1, b2)];
  double out[3];
  EvaluateT<double>(b1, b2, out);
  return {out[0], out[1], out[2]};
}

SurfacePoint G1Patch::EvaluateWithDerivatives(double b1, double b2) const {
  SurfacePoint r;
  const double b0 = 1.0 - b1 - b2;
  if (AtCorner(b0, b1, b2)) {
    // At vertex i the surface's differential is given by the two boundary-curve
    // tangents: dX = sum_l T_il db_l. d/db1 is db = (-1, 1, 0), d/db2 is (-1, 0, 1).
    const int i = CornerIndex(b0, b1, b2);
    std::array<Eigen::Vector3d, 3> t;
    for (int l = 0; l < 3; ++l) {
      t[l] = l == i ? Eigen::Vector3d::Zero() : HermiteEndTangent(x_[i], x_[l], n_[i]);
    }
    r.point = x_[i];
    r.d_b1 = t[1] - t[0];
    r.d_b2 = t[2] - t[0];
  } else {
    Jet out[3];
    EvaluateT<Jet>(Jet(b1, 1.0, 0.0), Jet(b2, 0.0, 1.0), out);
    r.point = {out[0].v, out[1].v, out[2].v};
    r.d_b1 = {out[0].d1, out[1].d1, out[2].d1};
    r.d_b2 = {out[0].d2, out[1].d2, out[2].d2};
  }
  r.normal = r.d_b1.cross(r.d_b2).normalized();
  return r;
}

template void G1Patch::EvaluateT<double>(const double&, const double&, double[3]) const;

}  // namespace facets
