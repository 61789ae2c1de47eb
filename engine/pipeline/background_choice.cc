#include "engine/pipeline/background_choice.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "io/image_io.h"

namespace facets {
namespace {

constexpr int kStripRows = 256;  // rows decoded at a time

// Largest grey value of an image file's scale: 255 for 8 bit, 65535 for 16 bit, 1 for float.
double FullScale(int bits) { return bits <= 16 ? std::ldexp(1.0, bits) - 1.0 : 1.0; }

// Adds the grey values of one image's border band to `histogram` (bins over 0..full_scale).
void AddBorder(const BlockImage& image, const Camera& camera, double full_scale, std::vector<long long>* histogram) {
  const int band = std::max(1, static_cast<int>(kBorderBandShare * std::min(camera.width, camera.height)));
  const double to_bin = (kHistogramBins - 1) / full_scale;
  ForEachImageStrip(image.path, kStripRows, 0, [&](const ImagePlanes& strip) {
    const ImagePlanes grey = strip.Grey();
    for (int y = grey.y0; y < grey.y0 + grey.height; ++y) {
      const bool whole_row = y < band || y >= camera.height - band;
      const float* row = grey.Row(0, y);
      for (int x = 0; x < grey.width; ++x) {
        if (!whole_row && x >= band && x < camera.width - band) x = camera.width - band;
        const int bin = static_cast<int>(std::lround(std::clamp(row[x] * to_bin, 0.0, kHistogramBins - 1.0)));
        ++(*histogram)[bin];
      }
    }
  });
}

// Grey value at quantile q of the histogram's pixels.
double HistogramQuantile(const std::vector<long long>& histogram, long long total, double q, double full_scale) {
  const long long wanted = static_cast<long long>(std::ceil(q * static_cast<double>(total)));
  long long seen = 0;
  for (size_t bin = 0; bin < histogram.size(); ++bin) {
    seen += histogram[bin];
    if (seen >= wanted) return static_cast<double>(bin) * full_scale / (kHistogramBins - 1);
  }
  return full_scale;
}

}  // namespace

BackgroundChoice ChooseBackground(const ImageBlock& block) {
  std::vector<long long> histogram(kHistogramBins, 0);
  double full_scale = 0.0;
  for (const BlockImage& image : block.images) {
    if (image.path.empty()) continue;
    const Camera& camera = block.CameraOf(image);
    const ImageHeader header = CheckImageHeader(image.path, camera);
    if (full_scale == 0.0) full_scale = FullScale(header.bits);
    if (FullScale(header.bits) != full_scale) {
      throw std::runtime_error(image.path + ": " + std::to_string(header.bits) +
                               "-bit image among images of another bit depth; the background is measured on one grey scale");
    }
    AddBorder(image, camera, full_scale, &histogram);
  }
  BackgroundChoice choice;
  for (long long n : histogram) choice.border_pixels += n;
  if (choice.border_pixels == 0) throw std::invalid_argument("choosing the background: no image file in the block");
  choice.hull_background = HistogramQuantile(histogram, choice.border_pixels, kHullQuantile, full_scale);
  choice.silhouette_background = HistogramQuantile(histogram, choice.border_pixels, kSilhouetteQuantile, full_scale);
  std::ostringstream why;
  why.precision(3);
  why << "frame border (" << choice.border_pixels << " pixels, " << kBorderBandShare * 100.0
      << " % of the shorter side): grey " << choice.hull_background << " at its " << kHullQuantile * 100.0
      << "th percentile (visual hull), " << choice.silhouette_background << " at its " << kSilhouetteQuantile * 100.0
      << "th (silhouette term)";
  choice.why = why.str();
  return choice;
}

}  // namespace facets
