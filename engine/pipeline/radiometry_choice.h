// The per-image radiometric model the images need, measured from their grey values at
// the tie points. Photographs whose exposure differs between shots need h0 and h1 per
// image (RadiometricModel::kLinear); images of one consistent exposure (rendered scenes)
// need none, and the linear model would only cost time there (about 2x).
//
// Measurement: up to kMaxRadiometryPoints tie points seen in >= 2 images, spread over
// object space; each observation's grey value is the mean of the 5 x 5 pixels around
// it (each image read once, as grey; windows with a pixel at 0 or full scale left out).
// Per image, a line g_image = h0 + h1 * g_mean from the point's mean grey value over its
// images to the image's, least squares with rejection beyond 3 robust sigmas (1.4826
// MAD). The images' brightness ratios at the points' mean grey value m, (h0 + h1 m) / m,
// spreading (10th to 90th percentile) beyond kLevelSpreadLinear choose kLinear.
#pragma once

#include <string>

#include "engine/solver/adjustment_options.h"
#include "io/image_block.h"

namespace facets {

// At most this many tie points are sampled; reading each image once costs the most
// (3 real sets of 11-28 images, up to 3072 x 2048: 6 s CPU together with the models).
inline constexpr int kMaxRadiometryPoints = 2000;
// 10th to 90th percentile range of the images' brightness ratios at the mean grey value
// above which kLinear is chosen (dimensionless: 0.03 = 3 %). Measured: rendered scenes of
// one exposure 0.5 % (stereo pair) and 1.8 % (oblique block); photographs 5.2 % (temple),
// 8.2 % (fountain), 27 % (kite aerials).
inline constexpr double kLevelSpreadLinear = 0.03;

struct RadiometryChoice {
  RadiometricModel model = RadiometricModel::kNone;
  // 10th-90th percentile range of the images' brightness ratios at the points' mean grey
  // value m, (h0 + h1 m) / m (dimensionless): what a change of exposure changes. Decides.
  double level_spread = 0.0;
  // 10th-90th percentile ranges of the gains h1 (dimensionless) and of the offsets h0 (as
  // a fraction of the full grey scale: 255 for 8 bit, 65535 for 16 bit). Reported only:
  // images of one exposure at different resolutions differ in contrast, which turns
  // their lines about m (rendered oblique block: h1 9.6 %, h0 4.2 %, brightness 1.8 %).
  double gain_spread = 0.0;
  double offset_spread = 0.0;
  int images_fitted = 0;       // images with enough observations for a line
  std::string why;             // the spreads and the decision in one line
};

// kNone with the reason when the block has no tie-point observations (project files
// without keypoints) or fewer than 2 images could be fitted.
RadiometryChoice ChooseRadiometry(const ImageBlock& block);

}  // namespace facets
