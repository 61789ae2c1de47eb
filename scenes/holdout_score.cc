// Held-out views: the scores of a rendering against the real image, and the report
// (scenes/holdout.h).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "scenes/holdout.h"

namespace facets {
namespace {

// Running sums of two value lists: enough for their means, variances and covariance.
struct PairSums {
  double n = 0, a = 0, b = 0, aa = 0, bb = 0, ab = 0;
  void Add(double x, double y) {
    n += 1;
    a += x;
    b += y;
    aa += x * x;
    bb += y * y;
    ab += x * y;
  }
  double VarA() const { return std::max(0.0, aa / n - (a / n) * (a / n)); }
  double VarB() const { return std::max(0.0, bb / n - (b / n) * (b / n)); }
  double Cov() const { return ab / n - (a / n) * (b / n); }
  double Zncc() const {
    const double denominator = std::sqrt(VarA() * VarB());
    return n > 0 && denominator > 0.0 ? std::clamp(Cov() / denominator, -1.0, 1.0) : kNoValue;
  }
};

void CheckSameSize(const ImagePlanes& real, const ImagePlanes& rendered) {
  if (real.width != rendered.width || real.height != rendered.height || real.channels != 1 ||
      rendered.channels != 1) {
    throw std::invalid_argument("holdout scores need two single-channel images of one size");
  }
}

// The window's ZNCC centred on (cx, cy), half side r; NaN when a pixel is not rendered or
// either side is flatter than min_std.
double WindowScore(const ImagePlanes& real, const ImagePlanes& rendered, int cx, int cy, int r,
                   double min_std) {
  PairSums sums;
  for (int y = cy - r; y <= cy + r; ++y) {
    for (int x = cx - r; x <= cx + r; ++x) {
      const float value = rendered.at(0, x, y);
      if (!std::isfinite(value)) return kNoValue;
      sums.Add(real.at(0, x, y), value);
    }
  }
  const double min_var = min_std * min_std;
  if (sums.VarA() < min_var || sums.VarB() < min_var) return kNoValue;
  return sums.Zncc();
}

std::string Number(double value, const char* format) {
  if (!std::isfinite(value)) return "-";
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

nlohmann::json JsonNumber(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

double MedianOver(const std::vector<HoldoutImageScore>& images, double (*value)(const HoldoutImageScore&)) {
  std::vector<double> values;
  for (const HoldoutImageScore& image : images) {
    if (std::isfinite(value(image))) values.push_back(value(image));
  }
  // The middle of an even count is the mean of its two middle values: with two held-out
  // images each column is their mean, not the lower one (which mixes images across columns).
  if (values.empty()) return kNoValue;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

}  // namespace

double Zncc(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) throw std::invalid_argument("Zncc: the two lists differ in length");
  PairSums sums;
  for (size_t i = 0; i < a.size(); ++i) sums.Add(a[i], b[i]);
  return sums.Zncc();
}

std::vector<double> WindowZncc(const ImagePlanes& real, const ImagePlanes& rendered, int window,
                               double min_std) {
  CheckSameSize(real, rendered);
  const int r = window / 2;
  const int rows = std::max(0, real.height - 2 * r);
  std::vector<std::vector<double>> per_row(rows);
  tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const auto& range) {
    for (int row = range.begin(); row != range.end(); ++row) {
      for (int x = r; x + r < real.width; ++x) {
        const double score = WindowScore(real, rendered, x, row + r, r, min_std);
        if (std::isfinite(score)) per_row[row].push_back(score);
      }
    }
  });
  std::vector<double> scores;
  for (const std::vector<double>& row : per_row) scores.insert(scores.end(), row.begin(), row.end());
  return scores;
}

LinearFit FitGainOffset(const ImagePlanes& real, const ImagePlanes& rendered) {
  CheckSameSize(real, rendered);
  PairSums sums;  // a: rendered, b: real
  for (size_t i = 0; i < rendered.data.size(); ++i) {
    if (std::isfinite(rendered.data[i])) sums.Add(rendered.data[i], real.data[i]);
  }
  LinearFit fit;
  fit.count = static_cast<long long>(sums.n);
  if (sums.n < 2) return fit;
  const double var_rendered = sums.VarA();
  fit.gain = var_rendered > 0.0 ? sums.Cov() / var_rendered : 0.0;
  fit.offset = sums.b / sums.n - fit.gain * sums.a / sums.n;
  // Residual variance of the least-squares line: var(real) - cov^2 / var(rendered).
  const double explained = var_rendered > 0.0 ? sums.Cov() * sums.Cov() / var_rendered : 0.0;
  fit.rms = std::sqrt(std::max(0.0, sums.VarB() - explained));
  return fit;
}

double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return kNoValue;
  const size_t k = static_cast<size_t>(std::floor(q * static_cast<double>(values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

HoldoutImageScore ScoreHoldoutImage(const std::string& name, const ImagePlanes& real,
                                    const ImagePlanes& rendered, const HoldoutOptions& options,
                                    const PixelMask* object) {
  CheckSameSize(real, rendered);
  HoldoutImageScore score;
  score.name = name;
  score.pixels = static_cast<long long>(rendered.data.size());
  for (float value : rendered.data) score.covered += std::isfinite(value) ? 1 : 0;
  const std::vector<double> zncc = WindowZncc(real, rendered, options.window, options.min_window_std);
  score.windows = static_cast<long long>(zncc.size());
  score.zncc_median = Quantile(zncc, 0.5);
  score.zncc_p10 = Quantile(zncc, 0.1);
  score.fit = FitGainOffset(real, rendered);
  if (object) {
    if (object->width != rendered.width || object->height != rendered.height) {
      throw std::invalid_argument(name + ": object mask and image differ in size");
    }
    score.object_pixels = object->Count();
    for (size_t i = 0; i < object->data.size(); ++i) {
      score.object_covered += object->data[i] && std::isfinite(rendered.data[i]) ? 1 : 0;
    }
  }
  return score;
}

void SummariseHoldout(HoldoutReport* report) {
  report->zncc_median = MedianOver(report->images, [](const HoldoutImageScore& s) { return s.zncc_median; });
  report->zncc_p10 = MedianOver(report->images, [](const HoldoutImageScore& s) { return s.zncc_p10; });
  report->rms = MedianOver(report->images, [](const HoldoutImageScore& s) { return s.fit.rms; });
  report->frame_coverage = MedianOver(report->images, [](const HoldoutImageScore& s) { return s.FrameCoverage(); });
  report->object_coverage = MedianOver(report->images, [](const HoldoutImageScore& s) { return s.ObjectCoverage(); });
}

std::string HoldoutReport::Table() const {
  std::ostringstream out;
  out << "held-out views of " << (mesh_name.empty() ? "the mesh" : mesh_name) << "\n";
  char line[256];
  std::snprintf(line, sizeof(line), "  %-28s %8s %8s %8s %8s %8s %8s %9s\n", "image", "ZNCC med", "ZNCC p10",
                "RMS", "gain", "offset", "cover %", "object %");
  out << line;
  auto row = [&](const std::string& name, double median, double p10, double rms, double gain, double offset,
                 double cover, double object) {
    std::snprintf(line, sizeof(line), "  %-28s %8s %8s %8s %8s %8s %8s %9s\n", name.c_str(),
                  Number(median, "%.3f").c_str(), Number(p10, "%.3f").c_str(), Number(rms, "%.2f").c_str(),
                  Number(gain, "%.3f").c_str(), Number(offset, "%.1f").c_str(),
                  Number(100 * cover, "%.1f").c_str(), Number(100 * object, "%.1f").c_str());
    out << line;
  };
  for (const HoldoutImageScore& s : images) {
    row(s.name, s.zncc_median, s.zncc_p10, s.fit.rms, s.fit.gain, s.fit.offset, s.FrameCoverage(),
        s.ObjectCoverage());
  }
  row("median over images", zncc_median, zncc_p10, rms, kNoValue, kNoValue, frame_coverage, object_coverage);
  return out.str();
}

std::string HoldoutReport::Json() const {
  nlohmann::json images_json = nlohmann::json::array();
  for (const HoldoutImageScore& s : images) {
    images_json.push_back({{"name", s.name},
                           {"pixels", s.pixels},
                           {"covered", s.covered},
                           {"windows", s.windows},
                           {"zncc_median", JsonNumber(s.zncc_median)},
                           {"zncc_p10", JsonNumber(s.zncc_p10)},
                           {"rms", JsonNumber(s.fit.rms)},
                           {"gain", JsonNumber(s.fit.gain)},
                           {"offset", JsonNumber(s.fit.offset)},
                           {"frame_coverage", s.FrameCoverage()},
                           {"object_pixels", s.object_pixels},
                           {"object_coverage", JsonNumber(s.ObjectCoverage())}});
  }
  nlohmann::json summary = {{"zncc_median", JsonNumber(zncc_median)}, {"zncc_p10", JsonNumber(zncc_p10)},
                            {"rms", JsonNumber(rms)},                 {"frame_coverage", JsonNumber(frame_coverage)},
                            {"object_coverage", JsonNumber(object_coverage)}};
  return nlohmann::json{{"holdout", {{"mesh", mesh_name}, {"images", images_json}, {"summary", summary}}}}.dump(2);
}

}  // namespace facets
