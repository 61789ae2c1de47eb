#include "scenes/albedo.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace facets {

namespace {

// Appends `components` sinusoids of one band, scaled to `contrast` standard deviation.
void AddBand(std::mt19937* rng, int components, double wavelength_min, double wavelength_max,
             double contrast, std::vector<double>* kx, std::vector<double>* ky,
             std::vector<double>* kz, std::vector<double>* phases,
             std::vector<double>* amplitudes) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double log_min = std::log(wavelength_min);
  const double log_max = std::log(wavelength_max);
  const size_t first = amplitudes->size();
  double sum_sq = 0;
  for (int i = 0; i < components; ++i) {
    const double z = 2 * unit(*rng) - 1;
    const double phi = 2 * M_PI * unit(*rng);
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    const Eigen::Vector3d dir(r * std::cos(phi), r * std::sin(phi), z);
    const double wavelength = std::exp(log_min + (log_max - log_min) * unit(*rng));
    const Eigen::Vector3d k = dir * (2 * M_PI / wavelength);
    kx->push_back(k.x());
    ky->push_back(k.y());
    kz->push_back(k.z());
    phases->push_back(2 * M_PI * unit(*rng));
    // Equal amplitudes over a log-uniform band: a pink-ish spectrum, like real texture.
    amplitudes->push_back(1.0);
    sum_sq += 0.5;  // variance of a unit sinusoid with random phase
  }
  const double scale = contrast / std::sqrt(sum_sq);
  for (size_t i = first; i < amplitudes->size(); ++i) (*amplitudes)[i] *= scale;
}

}  // namespace

ProceduralAlbedo::ProceduralAlbedo(const AlbedoOptions& options) : options_(options) {
  std::mt19937 rng(static_cast<unsigned>(options.seed) * 2654435761u + 17u);
  AddBand(&rng, options.components, options.wavelength_min, options.wavelength_max,
          options.contrast, &kx_, &ky_, &kz_, &phases_, &amplitudes_);
  // Extra bands draw from their own streams: the main band stays as it always was.
  for (size_t b = 0; b < options.extra_bands.size(); ++b) {
    const AlbedoBand& band = options.extra_bands[b];
    std::mt19937 band_rng(static_cast<unsigned>(options.seed) * 2654435761u + 1000003u * (b + 1));
    AddBand(&band_rng, band.components, band.wavelength_min, band.wavelength_max, band.contrast,
            &kx_, &ky_, &kz_, &phases_, &amplitudes_);
  }
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
