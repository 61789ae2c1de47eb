#include "engine/pipeline/radiometry_choice.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <array>
#include <string>
#include <limits>
#include <map>
#include <new>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "io/image_io.h"

namespace facets {
namespace {

constexpr int kHalfWindow = 2;           // 5 x 5 pixel window around an observation
constexpr int kMinObservationsPerImage = 20;
constexpr int kRejectionRounds = 4;
constexpr double kRejectSigmas = 3.0;    // robust sigmas (1.4826 MAD)

struct Observation {
  int point = 0;  // index into the sampled points
  int image = 0;  // index into block.images
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  double grey = std::numeric_limits<double>::quiet_NaN();
};

// Linear-interpolated quantile q in [0, 1] of v (not empty).
double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double at = std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(at));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (at - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

double Median(const std::vector<double>& v) { return Quantile(v, 0.5); }

// Observations (image index, keypoint) of one tie point that an image file can give.
std::vector<std::pair<int, Eigen::Vector2d>> UsableTrack(
    const ImageBlock& block, const TiePoint& point, const std::unordered_map<int, int>& index_of) {
  std::vector<std::pair<int, Eigen::Vector2d>> track;
  for (const TrackElement& element : point.track) {
    const auto it = index_of.find(element.image_id);
    if (it == index_of.end()) continue;
    const BlockImage& image = block.images[it->second];
    if (image.path.empty() || element.point2d_idx < 0 ||
        element.point2d_idx >= static_cast<int>(image.keypoints.size())) {
      continue;
    }
    track.emplace_back(it->second, image.keypoints[element.point2d_idx].xy);
  }
  return track;
}

// Of the candidate tie points, at most max_points spread over object space: one per
// cube of a grid (the one seen in the most images), the cube edge grown by 2^(1/3) from
// 1/256 of the points' extent until no more than max_points cubes are occupied.
std::vector<int> SpreadPoints(const ImageBlock& block, const std::vector<int>& candidates,
                              const std::vector<int>& track_length, int max_points) {
  if (static_cast<int>(candidates.size()) <= max_points) return candidates;
  Eigen::Vector3d lo = block.points[candidates[0]].xyz, hi = lo;
  for (int c : candidates) {
    lo = lo.cwiseMin(block.points[c].xyz);
    hi = hi.cwiseMax(block.points[c].xyz);
  }
  double cell = std::max((hi - lo).maxCoeff() / 256.0, 1e-9);
  for (;;) {
    std::map<std::array<long long, 3>, int> best;  // cube -> index into candidates
    for (size_t i = 0; i < candidates.size(); ++i) {
      const Eigen::Vector3d q = (block.points[candidates[i]].xyz - lo) / cell;
      const std::array<long long, 3> key = {static_cast<long long>(q.x()),
                                            static_cast<long long>(q.y()),
                                            static_cast<long long>(q.z())};
      auto [it, inserted] = best.try_emplace(key, static_cast<int>(i));
      if (!inserted && track_length[i] > track_length[it->second]) it->second = static_cast<int>(i);
    }
    if (static_cast<int>(best.size()) <= max_points) {
      std::vector<int> chosen;
      for (const auto& [key, i] : best) chosen.push_back(candidates[i]);
      std::sort(chosen.begin(), chosen.end());
      return chosen;
    }
    cell *= std::cbrt(2.0);
  }
}

// Observations of up to kMaxRadiometryPoints spread tie points seen in >= 2 images;
// Observation::point numbers the chosen points 0, 1, ...
std::vector<Observation> CollectObservations(const ImageBlock& block, int* point_count) {
  std::unordered_map<int, int> index_of;
  for (size_t i = 0; i < block.images.size(); ++i) index_of[block.images[i].image_id] = static_cast<int>(i);
  std::vector<int> candidates, track_length;
  for (size_t p = 0; p < block.points.size(); ++p) {
    const size_t usable = UsableTrack(block, block.points[p], index_of).size();
    if (usable < 2) continue;
    candidates.push_back(static_cast<int>(p));
    track_length.push_back(static_cast<int>(usable));
  }
  const std::vector<int> chosen = SpreadPoints(block, candidates, track_length, kMaxRadiometryPoints);
  std::vector<Observation> observations;
  for (size_t k = 0; k < chosen.size(); ++k) {
    for (const auto& [image, xy] : UsableTrack(block, block.points[chosen[k]], index_of)) {
      observations.push_back({static_cast<int>(k), image, xy, std::numeric_limits<double>::quiet_NaN()});
    }
  }
  *point_count = static_cast<int>(chosen.size());
  return observations;
}

// Largest grey value of an image file's scale: 255 for 8 bit, 65535 for 16 bit, 1 for float.
double FullScale(int bits) { return bits <= 16 ? std::ldexp(1.0, bits) - 1.0 : 1.0; }

// Mean of the 5 x 5 pixels around pixel (cx, cy), a window inside `grey` (rows of the
// image); NaN when it holds a clipped pixel (0 or full scale: under- or overexposed).
double WindowMean(const ImagePlanes& grey, int cx, int cy, double full_scale) {
  double sum = 0.0;
  for (int y = cy - kHalfWindow; y <= cy + kHalfWindow; ++y) {
    for (int x = cx - kHalfWindow; x <= cx + kHalfWindow; ++x) {
      const double g = grey.at(0, x, y);
      if (g <= 0.0 || g >= full_scale) return std::numeric_limits<double>::quiet_NaN();
      sum += g;
    }
  }
  return sum / ((2 * kHalfWindow + 1) * (2 * kHalfWindow + 1));
}

// Rows of an image read at a time: the windows are sampled strip by strip, so that a
// large image is never decoded whole.
constexpr int kSampleStripRows = 256;

// Fills the observations' grey values from one image (windows leaving the image stay NaN);
// returns the image's full grey scale.
double SampleImage(const std::string& path, const Camera& camera, const std::vector<Observation*>& observations) {
  const ImageHeader header = ReadImageHeader(path);
  if (header.width != camera.width || header.height != camera.height) {
    throw std::runtime_error(path + ": image is " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                             " pixels but camera " + std::to_string(camera.camera_id) + " expects " +
                             std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
  const double full_scale = FullScale(header.bits);
  std::vector<Observation*> inside;
  for (Observation* o : observations) {
    const int cx = static_cast<int>(std::floor(o->xy.x())), cy = static_cast<int>(std::floor(o->xy.y()));
    if (cx - kHalfWindow >= 0 && cy - kHalfWindow >= 0 && cx + kHalfWindow < header.width &&
        cy + kHalfWindow < header.height) {
      inside.push_back(o);
    }
  }
  std::vector<bool> done(inside.size(), false);
  // Strips overlap by a window's rows, so every window lies whole in one of them.
  ForEachImageStrip(path, kSampleStripRows, 2 * kHalfWindow, [&](const ImagePlanes& strip) {
    const ImagePlanes grey = strip.Grey();
    for (size_t k = 0; k < inside.size(); ++k) {
      const Eigen::Vector2d& xy = inside[k]->xy;
      const int cx = static_cast<int>(std::floor(xy.x())), cy = static_cast<int>(std::floor(xy.y()));
      if (done[k] || cy - kHalfWindow < grey.y0 || cy + kHalfWindow >= grey.y0 + grey.height) continue;
      inside[k]->grey = WindowMean(grey, cx, cy, full_scale);
      done[k] = true;
    }
  });
  return full_scale;
}

// Fills Observation::grey, reading each image with observations once; returns the
// largest full grey scale of the images read.
double SampleGrey(const ImageBlock& block, std::vector<Observation>* observations) {
  std::vector<std::vector<Observation*>> of_image(block.images.size());
  for (Observation& o : *observations) of_image[o.image].push_back(&o);
  std::vector<double> full_scale(block.images.size(), 0.0);
  tbb::parallel_for(size_t{0}, block.images.size(), [&](size_t i) {
    if (of_image[i].empty()) return;
    try {
      full_scale[i] = SampleImage(block.images[i].path, block.CameraOf(block.images[i]), of_image[i]);
    } catch (const std::bad_alloc&) {
      throw std::runtime_error(block.images[i].path + ": out of memory reading the image (radiometry choice)");
    }
  });
  return *std::max_element(full_scale.begin(), full_scale.end());
}

// Per point, the mean grey value over its sampled observations (NaN below 2).
std::vector<double> PointMeans(const std::vector<Observation>& observations, int point_count) {
  std::vector<double> sum(point_count, 0.0);
  std::vector<int> count(point_count, 0);
  for (const Observation& o : observations) {
    if (std::isnan(o.grey)) continue;
    sum[o.point] += o.grey;
    ++count[o.point];
  }
  std::vector<double> mean(point_count, std::numeric_limits<double>::quiet_NaN());
  for (int p = 0; p < point_count; ++p) {
    if (count[p] >= 2) mean[p] = sum[p] / count[p];
  }
  return mean;
}

struct Line {
  double h0 = 0.0, h1 = 1.0;
  bool ok = false;
};

// Least-squares line y = h0 + h1 x over the pairs flagged in `use`.
Line FitLine(const std::vector<double>& x, const std::vector<double>& y, const std::vector<bool>& use) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    if (!use[i]) continue;
    n += 1;
    sx += x[i];
    sy += y[i];
  }
  if (n < kMinObservationsPerImage) return {};
  const double mx = sx / n, my = sy / n;
  for (size_t i = 0; i < x.size(); ++i) {
    if (!use[i]) continue;
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  if (!(sxx > 0)) return {};
  const double h1 = sxy / sxx;
  return {my - h1 * mx, h1, true};
}

// The line fitted again after each round of rejecting pairs beyond kRejectSigmas robust
// sigmas of its residuals.
Line FitRobustLine(const std::vector<double>& x, const std::vector<double>& y) {
  std::vector<bool> use(x.size(), true);
  Line line = FitLine(x, y, use);
  for (int round = 0; round < kRejectionRounds && line.ok; ++round) {
    std::vector<double> residual(x.size()), deviation;
    for (size_t i = 0; i < x.size(); ++i) residual[i] = y[i] - (line.h0 + line.h1 * x[i]);
    const double centre = Median(residual);
    for (double r : residual) deviation.push_back(std::abs(r - centre));
    const double sigma = 1.4826 * Median(deviation);
    if (!(sigma > 0)) break;
    for (size_t i = 0; i < x.size(); ++i) use[i] = std::abs(residual[i] - centre) <= kRejectSigmas * sigma;
    line = FitLine(x, y, use);
  }
  return line;
}

// Per image, the robust line from the points' mean grey value to the image's.
std::vector<Line> FitImageLines(const std::vector<Observation>& observations,
                                const std::vector<double>& point_mean, size_t image_count) {
  std::vector<std::vector<double>> x(image_count), y(image_count);
  for (const Observation& o : observations) {
    if (std::isnan(o.grey) || std::isnan(point_mean[o.point])) continue;
    x[o.image].push_back(point_mean[o.point]);
    y[o.image].push_back(o.grey);
  }
  std::vector<Line> lines(image_count);
  for (size_t i = 0; i < image_count; ++i) {
    if (x[i].size() >= static_cast<size_t>(kMinObservationsPerImage)) lines[i] = FitRobustLine(x[i], y[i]);
  }
  return lines;
}

// Mean of the values that are numbers (not NaN).
double MeanOfNumbers(const std::vector<double>& values) {
  double sum = 0.0;
  int count = 0;
  for (double v : values) {
    if (std::isnan(v)) continue;
    sum += v;
    ++count;
  }
  return count > 0 ? sum / count : std::numeric_limits<double>::quiet_NaN();
}

// 10th to 90th percentile range.
double PercentileRange(const std::vector<double>& values) {
  return Quantile(values, 0.9) - Quantile(values, 0.1);
}

RadiometryChoice NoneBecause(const std::string& why) {
  RadiometryChoice choice;
  choice.why = why;
  return choice;
}

}  // namespace

RadiometryChoice ChooseRadiometry(const ImageBlock& block) {
  int point_count = 0;
  std::vector<Observation> observations = CollectObservations(block, &point_count);
  if (observations.empty()) return NoneBecause("no tie-point observations");
  const double full_scale = SampleGrey(block, &observations);
  const std::vector<double> point_mean = PointMeans(observations, point_count);
  const std::vector<Line> lines = FitImageLines(observations, point_mean, block.images.size());
  const double mean_grey = MeanOfNumbers(point_mean);
  std::vector<double> levels, gains, offsets;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (!lines[i].ok) continue;
    levels.push_back((lines[i].h0 + lines[i].h1 * mean_grey) / mean_grey);
    gains.push_back(lines[i].h1);
    offsets.push_back(lines[i].h0 / full_scale);
  }
  RadiometryChoice choice;
  choice.images_fitted = static_cast<int>(levels.size());
  if (choice.images_fitted < 2) {
    choice.why = "fewer than 2 images with " + std::to_string(kMinObservationsPerImage) +
                 " tie-point grey values";
    return choice;
  }
  choice.level_spread = PercentileRange(levels);
  choice.gain_spread = PercentileRange(gains);
  choice.offset_spread = PercentileRange(offsets);
  const bool linear = choice.level_spread > kLevelSpreadLinear;
  choice.model = linear ? RadiometricModel::kLinear : RadiometricModel::kNone;
  char line[320];
  std::snprintf(line, sizeof line,
                "brightness at the mean grey %.0f spreads %.1f %% (limit %.1f %%; gains h1 %.1f %%, "
                "offsets h0 %.1f %% of the grey scale) over %d images, %d tie points: %s",
                mean_grey, 100 * choice.level_spread, 100 * kLevelSpreadLinear, 100 * choice.gain_spread,
                100 * choice.offset_spread, choice.images_fitted, point_count, linear ? "linear" : "none");
  choice.why = line;
  return choice;
}

}  // namespace facets
