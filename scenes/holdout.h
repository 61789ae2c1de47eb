// Held-out views: a ground-truth-free accuracy measure for a mesh seen by real
// photographs (`facets evaluate --holdout`, docs/EVALUATION.md "Held-out views").
//
// For each held-out image H (io/image_subset.h selects them; the reconstruction should
// not have seen them: `facets reconstruct --exclude-images` with the same selection):
// 1. Render: one ray per pixel of H through the pixel centre (lens distortion removed,
//    visibility/pixel_cast.h PixelRays) against the mesh (Embree, first hit, either
//    side). Pixels whose ray misses, or hits outside the region of interest, are not
//    covered.
// 2. Colour: the hit point takes the grey value the other (not held-out) images record
//    there: the mean of their bilinear samples at the point's projection, over the images
//    that see it (in front, inside the frame, the surface facing them with |cos| >=
//    min_cos_incidence, no triangle between the point and the projection centre: an
//    Embree occlusion ray), each weighted by that cosine (a grazing view smears a pixel
//    over a long strip of surface). This is the textured mesh a viewer would show,
//    sampled at H's pixels; a point no other image sees stays uncovered.
// 3. Compare with H's own grey values (mean of the channels):
//    - ZNCC over every square window (side `window`, 7) whose pixels are all covered and
//      in which both images vary (standard deviation >= min_window_std grey values):
//      median and 10th percentile. Invariant to a gain and offset per window.
//    - RMS of the grey residual after a linear radiometric fit over the covered pixels:
//      real = gain * rendered + offset (least squares), for exposure differences.
//    - Coverage: covered pixels over the frame; with a foreground definition
//      (visibility/silhouette.h ForegroundMask), also covered foreground pixels over the
//      foreground.
// A wrong surface sends a pixel's ray to the wrong place in the other images, so the
// rendered texture is misaligned and blurred against H: ZNCC drops, RMS grows.
//
// Units: grey values in the image files' own scale (0..255 for 8 bit); coordinates in
// the block's local frame.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "io/image_block.h"
#include "io/image_io.h"
#include "io/image_subset.h"
#include "visibility/silhouette.h"

namespace facets {

class TriangleScene;

struct HoldoutOptions {
  std::string images = kDefaultHoldoutSpec;  // held-out selection (io/image_subset.h)
  std::optional<RegionOfInterest> roi;       // local frame; hits outside are uncovered
  int window = 7;                            // ZNCC window side, pixels, odd >= 3
  double min_window_std = 1.0;               // grey values; flatter windows are skipped
  double min_cos_incidence = 0.1;            // 84.3 degrees off the normal at most
  std::optional<ForegroundOptions> foreground;  // object pixels for the object coverage
  std::string render_dir;  // when set: each held-out image's rendering as STEM_holdout.png
  void Check() const;      // throws std::invalid_argument naming the option
};

constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

// real = gain * rendered + offset by least squares; rms of the residual (grey values).
struct LinearFit {
  double gain = kNoValue, offset = kNoValue, rms = kNoValue;
  long long count = 0;
};

struct HoldoutImageScore {
  std::string name;
  long long pixels = 0;          // of the frame
  long long covered = 0;         // with a rendered grey value
  long long windows = 0;         // ZNCC windows scored
  double zncc_median = kNoValue, zncc_p10 = kNoValue;
  LinearFit fit;
  long long object_pixels = -1;  // foreground pixels; -1 without a foreground definition
  long long object_covered = 0;  // foreground pixels with a rendered grey value

  double FrameCoverage() const { return pixels > 0 ? double(covered) / pixels : 0.0; }
  double ObjectCoverage() const {
    return object_pixels > 0 ? double(object_covered) / object_pixels : kNoValue;
  }
};

struct HoldoutReport {
  std::string mesh_name;
  std::vector<HoldoutImageScore> images;
  // Over the held-out images: the median of each image's value (NaN when no image has one).
  double zncc_median = kNoValue, zncc_p10 = kNoValue, rms = kNoValue;
  double frame_coverage = kNoValue, object_coverage = kNoValue;

  std::string Table() const;
  std::string Json() const;
};

// Zero-normalised cross-correlation of two equally long value lists; NaN when either has
// no variance.
double Zncc(const std::vector<float>& a, const std::vector<float>& b);

// ZNCC of every `window` x `window` window (all centres) where every pixel of `rendered`
// is finite and both standard deviations reach min_std. Single-channel planes of equal size.
std::vector<double> WindowZncc(const ImagePlanes& real, const ImagePlanes& rendered, int window,
                               double min_std);

// The least-squares gain and offset of `real` against the finite pixels of `rendered`.
LinearFit FitGainOffset(const ImagePlanes& real, const ImagePlanes& rendered);

// The q-quantile (0..1) of values (sorted copy; the lower of the two neighbours); NaN if empty.
double Quantile(std::vector<double> values, double q);

// Scores one held-out image from its grey plane and its rendering; object mask optional
// (empty = none).
HoldoutImageScore ScoreHoldoutImage(const std::string& name, const ImagePlanes& real,
                                    const ImagePlanes& rendered, const HoldoutOptions& options,
                                    const PixelMask* object = nullptr);

// Fills the report's medians over its images.
void SummariseHoldout(HoldoutReport* report);

// The rendering of image `held_out` of `block` from the images `sources` (indices into
// block.images; their grey planes are greys[source]): one channel, NaN where not covered.
ImagePlanes RenderFromImages(const TriangleScene& scene, const ImageBlock& block, int held_out,
                             const std::vector<int>& sources, const std::vector<ImagePlanes>& greys,
                             const HoldoutOptions& options);

// The whole measure: mesh (local frame of `block`) against the held-out images of the
// block (files at BlockImage::path). Throws std::invalid_argument when the selection is
// empty or names every image, and std::runtime_error naming an unreadable image.
HoldoutReport EvaluateHoldout(const ImageBlock& block, const std::vector<Eigen::Vector3d>& vertices,
                              const std::vector<Eigen::Vector3i>& triangles,
                              const HoldoutOptions& options);

}  // namespace facets
