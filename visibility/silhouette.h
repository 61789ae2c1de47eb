// Silhouettes: where a mesh covers an image, where the image shows the object
// before a dark background, and how well the two agree (intersection over union).
//
// - Foreground: pixels whose grey value (mean over channels) exceeds a threshold of the
//   background; optionally only the largest 8-connected component (a backdrop's stray
//   bright specks, a grey cloth that does not touch the object) and components smaller
//   than a pixel count dropped; optionally a morphological opening first and small
//   enclosed background holes filled.
// - Coverage: one ray per pixel through the pixel centre (lens distortion removed,
//   visibility/pixel_cast.h PixelRays), covered when it hits any triangle of the mesh
//   (Embree, either side). Exact for any camera model, no rasterisation error.
// - IoU = |F and C| / |F or C| per image.
// Engine-free: used by `facets evaluate --silhouette` and by the visual-hull start.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "io/camera.h"
#include "io/image_block.h"
#include "io/image_io.h"
#include "io/rigid3d.h"

namespace facets {

class TriangleScene;

// A binary image: data[y * width + x] is 0 or 1.
struct PixelMask {
  int width = 0, height = 0;
  std::vector<uint8_t> data;

  PixelMask() = default;
  PixelMask(int w, int h) : width(w), height(h), data(static_cast<size_t>(w) * h, 0) {}
  uint8_t& at(int x, int y) { return data[static_cast<size_t>(y) * width + x]; }
  uint8_t at(int x, int y) const { return data[static_cast<size_t>(y) * width + x]; }
  long long Count() const;
};

struct ForegroundOptions {
  // A pixel is background when its grey value (mean of the channels) is <= this.
  double background_max = 15.0;
  // Keep only the largest 8-connected foreground component.
  bool largest_component = false;
  // Drop 8-connected foreground components of fewer pixels (0 = keep all).
  int min_component_pixels = 0;
  // Morphological opening (erosion, then dilation) with a (2r+1)^2 square before the
  // components are taken: cuts the hair-thin bridges a fuzzy cloth makes to the object.
  int open_radius = 0;
  // Background components (4-connected) of fewer pixels that do not touch the image
  // border become foreground: dark shadow specks inside the object (0 = off).
  int fill_holes_below = 0;
  void Check() const;  // throws std::invalid_argument naming the option
};

PixelMask ForegroundMask(const ImagePlanes& image, const ForegroundOptions& options);
// The component selection of ForegroundMask (largest_component, min_component_pixels).
void KeepComponents(PixelMask* mask, const ForegroundOptions& options);

// Labels of the 8-connected components of `mask` (0 = not in the mask, 1.. = component),
// and the pixel count of each label (sizes[0] unused).
std::vector<int> LabelComponents(const PixelMask& mask, std::vector<long long>* sizes);

// Pixels of a camera's image whose ray hits a triangle of `scene` (geometry 0 or
// occluders alike).
PixelMask CoverageMask(const TriangleScene& scene, const Camera& camera,
                       const Rigid3d& cam_from_world);

// Signed distance of every pixel centre to a mask's outline, in pixels: positive on
// background (outside), negative on the mask (inside); the outline lies half-way between
// a mask pixel and its background neighbour, so two such neighbours get -0.5 and +0.5.
// Exact Euclidean distances between pixel centres (separable squared-distance transform).
// Used by the silhouette term of the adjustment (AdjustmentOptions::silhouette_weight):
// where a rim of the surface projects against the outline.
struct SilhouetteDistance {
  int width = 0, height = 0;
  std::vector<float> value;  // value[y * width + x]
  float at(int x, int y) const { return value[static_cast<size_t>(y) * width + x]; }
  // Bilinear between pixel centres at a pixel position (centre of the top-left pixel at
  // (0.5, 0.5), io/camera.h), with its gradient (pixels per pixel); false outside the
  // centres' span.
  bool Sample(const Eigen::Vector2d& position, double* distance, Eigen::Vector2d* gradient) const;
};
SilhouetteDistance SignedDistanceToOutline(const PixelMask& mask);

// One image's silhouette as the adjustment uses it: the camera and pose of the image
// file (full size) and the signed distance to its foreground outline.
struct SilhouetteView {
  Camera camera;
  Rigid3d cam_from_world;
  SilhouetteDistance distance;
};

struct MaskComparison {
  long long foreground = 0;    // pixels of the image's foreground
  long long covered = 0;       // pixels the mesh covers
  long long intersection = 0;  // both
  long long union_ = 0;        // either
  double IoU() const { return union_ > 0 ? static_cast<double>(intersection) / union_ : 1.0; }
};
// Throws std::invalid_argument when the sizes differ.
MaskComparison CompareMasks(const PixelMask& foreground, const PixelMask& covered);

struct SilhouetteImage {
  std::string name;
  MaskComparison comparison;
};

struct SilhouetteReport {
  std::vector<SilhouetteImage> images;
  double min_iou = 0, median_iou = 0, mean_iou = 0;
  std::string worst_image;
  std::string Table() const;
  std::string Json() const;
};

// Statistics (min, median, mean) over the images of a report.
void SummariseSilhouettes(SilhouetteReport* report);

// Every image of `block` (files at BlockImage::path) against the mesh. mask_dir, when not
// empty, receives one PNG per image: 255 both, 170 foreground only, 85 mesh only.
// Errors name the image file.
SilhouetteReport EvaluateSilhouettes(const ImageBlock& block,
                                     const std::vector<Eigen::Vector3d>& vertices,
                                     const std::vector<Eigen::Vector3i>& triangles,
                                     const ForegroundOptions& options,
                                     const std::string& mask_dir = "");

}  // namespace facets
