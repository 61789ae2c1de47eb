// The grey level of the background behind a photographed object, measured where an
// object scene shows only background: the band along the frame's border. The visual
// hull and the silhouette term call a pixel background when its grey value (mean of the
// channels) is at or below a threshold; a fixed threshold either keeps a grey cloth or
// backdrop next to the object (the hull grows into it) or carves the object's shaded
// faces. The border's own brightness distribution says where the background ends.
//
// Measurement: every image read once, as grey, in strips; the pixels within
// kBorderBandShare of the shorter image side from any frame edge are pooled over the
// images into a histogram of kHistogramBins bins over the file's grey scale. The hull's
// threshold is the kHullQuantile of the border's grey values (an object that reaches
// into the band moves it little), the silhouette term's the higher kSilhouetteQuantile:
// the hull must not carve object, the outline term should not pull rims over the
// brightest background.
#pragma once

#include <string>

#include "io/image_block.h"

namespace facets {

// Share of the shorter image side taken as the border band (dimensionless).
inline constexpr double kBorderBandShare = 0.05;
// Quantiles of the border's grey values (dimensionless). Measured on the Middlebury
// temple (16 images, black backdrop, grey cloth at the sides): 0.98 gives grey 31.3 and
// 0.995 gives 38.7, where a hand search found 30 and 40 best.
inline constexpr double kHullQuantile = 0.98;
inline constexpr double kSilhouetteQuantile = 0.995;
inline constexpr int kHistogramBins = 4096;

struct BackgroundChoice {
  double hull_background = 0.0;        // grey values <= this are background for the hull
  double silhouette_background = 0.0;  // ... for the silhouette term
  long long border_pixels = 0;         // pixels of the border band pooled
  std::string why;                     // the measurement and the thresholds in one line
};

// Throws std::runtime_error naming the file when an image cannot be read or is not of its
// camera's size, std::invalid_argument when the block has no image with a file.
BackgroundChoice ChooseBackground(const ImageBlock& block);

}  // namespace facets
