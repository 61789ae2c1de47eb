#include "engine/search/patch_score.h"

#include <cmath>
#include <limits>

namespace facets {

bool SampleGrey(const ImagePlanes& image, const Eigen::Vector2d& position, double* grey) {
  const double u = position.x() - 0.5, v = position.y() - 0.5;
  const double fu = std::floor(u), fv = std::floor(v);
  const int x = static_cast<int>(fu), y = static_cast<int>(fv);
  if (!image.Holds(x, y) || !image.Holds(x + 1, y + 1)) return false;
  const double a = u - fu, b = v - fv;
  double sum = 0.0;
  for (int c = 0; c < image.channels; ++c) {
    sum += (1 - a) * (1 - b) * image.at(c, x, y) + a * (1 - b) * image.at(c, x + 1, y) +
           (1 - a) * b * image.at(c, x, y + 1) + a * b * image.at(c, x + 1, y + 1);
  }
  *grey = sum / image.channels;
  return true;
}

bool ImageHolds(const LevelImage& image, const Eigen::Vector3d& point) {
  const Eigen::Vector3d in_cam = image.cam_from_world * point;
  if (!(in_cam.z() > 0)) return false;
  const Eigen::Vector2d pixel = image.camera->ImageFromCam(in_cam);
  const double u = std::floor(pixel.x() - 0.5), v = std::floor(pixel.y() - 0.5);
  if (!(std::abs(u) < 1e9 && std::abs(v) < 1e9)) return false;  // NaN or far off
  const int x = static_cast<int>(u), y = static_cast<int>(v);
  return image.pixels->Holds(x, y) && image.pixels->Holds(x + 1, y + 1);
}

bool ImageHoldsPatch(const LevelImage& image, const Eigen::Vector3d& centre, const Eigen::Vector3d& normal,
                     double radius) {
  const auto [t1, t2] = TangentBasis(normal);
  for (double a : {-1.0, 1.0}) {
    for (double b : {-1.0, 1.0}) {
      if (!ImageHolds(image, centre + radius * (a * t1 + b * t2))) return false;
    }
  }
  return true;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> TangentBasis(const Eigen::Vector3d& normal) {
  const Eigen::Vector3d t1 = normal.unitOrthogonal();
  return {t1, normal.cross(t1)};
}

std::vector<Eigen::Vector3d> PatchOffsets(const Eigen::Vector3d& normal, int half, double spacing) {
  const auto [t1, t2] = TangentBasis(normal);
  std::vector<Eigen::Vector3d> offsets;
  offsets.reserve((2 * half + 1) * (2 * half + 1));
  for (int i = -half; i <= half; ++i) {
    for (int j = -half; j <= half; ++j) offsets.push_back(spacing * (i * t1 + j * t2));
  }
  return offsets;
}

double PatchScorer::Score(const std::vector<Eigen::Vector3d>& samples) {
  const size_t n = samples.size();
  sum_.assign(n, 0.0);
  g_.resize(n);
  std::vector<double>& g = g_;
  int used = 0;
  for (const LevelImage* image : images_) {
    bool ok = true;
    for (size_t s = 0; s < n && ok; ++s) {
      const Eigen::Vector3d in_cam = image->cam_from_world * samples[s];
      ok = in_cam.z() > 0 && SampleGrey(*image->pixels, image->camera->ImageFromCam(in_cam), &g[s]);
    }
    if (!ok) return -std::numeric_limits<double>::infinity();
    double mean = 0.0;
    for (double x : g) mean += x;
    mean /= n;
    double ss = 0.0;
    for (double& x : g) {
      x -= mean;
      ss += x * x;
    }
    if (std::sqrt(ss / n) < min_contrast_) continue;  // flat here: no information
    const double scale = 1.0 / std::sqrt(ss);
    for (size_t s = 0; s < n; ++s) sum_[s] += g[s] * scale;
    ++used;
  }
  if (used < min_images_) return -std::numeric_limits<double>::infinity();
  double norm2 = 0.0;
  for (double x : sum_) norm2 += x * x;
  // |sum z_i|^2 = K + sum_{i != j} z_i . z_j: the mean of the K (K - 1) pairwise NCCs.
  return (norm2 - used) / (static_cast<double>(used) * (used - 1));
}

}  // namespace facets
