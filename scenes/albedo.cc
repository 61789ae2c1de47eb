#include "scenes/albedo.h"

#include <cmath>
#include <random>

namespace facets {

ProceduralAlbedo::ProceduralAlbedo(const AlbedoOptions& options) : options_(options) {
  std::mt19937 rng(static_cast<unsigned>(options.seed) * 2654435761u + 17u);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double log_min = std::log(options.wavelength_min);
  const double log_max = std::log(options.wavelength_max);
  double sum_sq = 0;
  for (int i = 0; i < options.components; ++i) {
    const double z = 2 * unit(rng) - 1;
    const double phi = 2 * M_PI * unit(rng);
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    const Eigen::Vector3d dir(r * std::cos(phi), r * std::sin(phi), z);
    const double wavelength = std::exp(log_min + (log_max - log_min) * unit(rng));
    const Eigen::Vector3d k = dir * (2 * M_PI / wavelength);
    kx_.push_back(k.x());
    ky_.push_back(k.y());
    kz_.push_back(k.z());
    phases_.push_back(2 * M_PI * unit(rng));
    // Equal amplitudes over a log-uniform band: a pink-ish spectrum, like real texture.
    amplitudes_.push_back(1.0);
    sum_sq += 0.5;  // variance of a unit sinusoid with random phase
  }
  const double scale = options.contrast / std::sqrt(sum_sq);
  for (double& a : amplitudes_) a *= scale;
}

double ProceduralAlbedo::Texture(const Eigen::Vector3d& p) const {
  const double x = p.x(), y = p.y(), z = p.z();
  const size_t n = kx_.size();
  double sum = 0;
  for (size_t i = 0; i < n; ++i) {
    sum += amplitudes_[i] * FastSin(kx_[i] * x + ky_[i] * y + kz_[i] * z + phases_[i]);
  }
  return options_.mean + sum;
}

double ProceduralAlbedo::operator()(const Eigen::Vector3d& p) const {
  for (const AlbedoPatch& patch : options_.patches) {
    if (patch.Contains(p)) return patch.albedo;
  }
  const double a = Texture(p);
  return a < 0 ? 0 : (a > 1 ? 1 : a);
}

}  // namespace facets
