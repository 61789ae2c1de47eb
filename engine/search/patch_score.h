// Photo-consistency of a small planar patch in object space: the mean pairwise
// normalised cross-correlation of the grey values the images see at its samples (object
// lifting of seed 001, per patch). Shared by the searches between pyramid levels
// (engine/search/normal_search.h, engine/search/plane_propagation.h).
#pragma once

#include <Eigen/Core>

#include <utility>
#include <vector>

#include "engine/images/level_image.h"
#include "io/image_io.h"

namespace facets {

// Mean over channels, bilinear between pixel centres (pixel x covers [x, x + 1)).
// False when the 2 x 2 neighbourhood is not all held.
bool SampleGrey(const ImagePlanes& image, const Eigen::Vector2d& position, double* grey);

// Whether `image` can sample the grey value at `point`: in front of its camera and the
// 2 x 2 neighbourhood of its projection held (what SampleGrey needs).
bool ImageHolds(const LevelImage& image, const Eigen::Vector3d& point);

// Whether `image` holds the whole square patch of half-width `radius` around `centre`
// in the plane normal to `normal` (its four corners: the patch is convex and so is the
// frame).
bool ImageHoldsPatch(const LevelImage& image, const Eigen::Vector3d& centre, const Eigen::Vector3d& normal,
                     double radius);

// Two unit vectors spanning the tangent plane of a unit normal (a patch's axes).
std::pair<Eigen::Vector3d, Eigen::Vector3d> TangentBasis(const Eigen::Vector3d& normal);

// Offsets of a square patch of (2 half + 1)^2 samples `spacing` apart in the plane
// normal to `normal`, around 0.
std::vector<Eigen::Vector3d> PatchOffsets(const Eigen::Vector3d& normal, int half, double spacing);

// Scores sample sets against a fixed list of images. Not thread-safe (buffers reused):
// one per thread.
class PatchScorer {
 public:
  // Images whose grey values at the samples vary by less than `min_contrast` (standard
  // deviation) carry no information and are left out; fewer than `min_images` left:
  // no score.
  PatchScorer(const std::vector<const LevelImage*>& images, double min_contrast, int min_images)
      : images_(images), min_contrast_(min_contrast), min_images_(min_images) {}

  // Mean pairwise NCC over the images; -infinity when an image does not hold every
  // sample (a sample behind its camera or off its frame) or too few images have contrast.
  double Score(const std::vector<Eigen::Vector3d>& samples);

 private:
  const std::vector<const LevelImage*>& images_;
  double min_contrast_;
  int min_images_;
  std::vector<double> sum_;
  std::vector<double> g_;  // one image's grey values at the samples (reused)
};

}  // namespace facets
