// Band-limited procedural albedo in 3D object space, and Lambertian sun shading.
//
// The texture is a sum of `components` random 3D sinusoids (directions uniform on
// the sphere, wavelengths log-uniform in [wavelength_min, wavelength_max], phases
// uniform) scaled to a standard deviation of `contrast` around `mean` and clamped to
// [0, 1]. Being defined in 3D it needs no parameterisation of the surface and looks
// alike on roofs, walls and curved objects. Constant-albedo patches override it.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "scenes/scene.h"

namespace facets {

class ProceduralAlbedo {
 public:
  explicit ProceduralAlbedo(const AlbedoOptions& options);
  // Albedo in [0, 1] at a point (local object coordinates).
  double operator()(const Eigen::Vector3d& point) const;
  // The texture alone (no patches, no clamping).
  double Texture(const Eigen::Vector3d& point) const;

 private:
  AlbedoOptions options_;
  // Structure of arrays so the sum vectorises: wave vector (2 pi / wavelength *
  // direction), phase and amplitude per component.
  std::vector<double> kx_, ky_, kz_, phases_, amplitudes_;
};

// sin(x) to 1e-9 absolute for |x| < 1e6: reduction by pi and a degree-13 Taylor
// polynomial. Branch-free so loops over it vectorise; 5-10x faster than std::sin,
// which dominated the rendering time.
inline double FastSin(double x) {
  constexpr double kInvPi = 0.31830988618379067154;
  constexpr double kPiHi = 3.141592653589793116;  // pi = kPiHi + kPiLo
  constexpr double kPiLo = 1.2246467991473532e-16;
  // Adding and subtracting 1.5 * 2^52 rounds to the nearest integer (no libm call).
  constexpr double kRound = 6755399441055744.0;
  const double k = (x * kInvPi + kRound) - kRound;
  const double r = (x - k * kPiHi) - k * kPiLo;  // in [-pi/2, pi/2]
  const double r2 = r * r;
  const double p =
      r * (1 + r2 * (-1.0 / 6 + r2 * (1.0 / 120 + r2 * (-1.0 / 5040 + r2 * (1.0 / 362880 +
          r2 * (-1.0 / 39916800 + r2 * (1.0 / 6227020800.0)))))));
  // sin(k pi + r) = (-1)^k sin(r); |k - 2 round(k / 2)| is 1 for odd k, 0 for even.
  const double half = (0.5 * k + kRound) - kRound;
  return p * (1 - 2 * std::abs(k - 2 * half));
}

// I = albedo * (ambient + (1 - ambient) * max(0, n . s)), n and s unit vectors.
inline double LambertShading(double albedo, const Eigen::Vector3d& normal,
                             const SunOptions& sun, const Eigen::Vector3d& sun_direction) {
  const double ns = normal.dot(sun_direction);
  return albedo * (sun.ambient + (1.0 - sun.ambient) * (ns > 0 ? ns : 0.0));
}

}  // namespace facets
