#include "visibility/silhouette.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "visibility/embree_scene.h"
#include "visibility/pixel_cast.h"

namespace facets {

long long PixelMask::Count() const {
  long long n = 0;
  for (uint8_t v : data) n += v ? 1 : 0;
  return n;
}

void ForegroundOptions::Check() const {
  if (!std::isfinite(background_max)) {
    throw std::invalid_argument("background threshold must be finite");
  }
  if (min_component_pixels < 0) {
    throw std::invalid_argument("minimum component size must be >= 0");
  }
  if (open_radius < 0) throw std::invalid_argument("opening radius must be >= 0");
  if (fill_holes_below < 0) throw std::invalid_argument("hole size must be >= 0");
}

std::vector<int> LabelComponents(const PixelMask& mask, std::vector<long long>* sizes) {
  const int w = mask.width, h = mask.height;
  std::vector<int> label(mask.data.size(), 0);
  sizes->assign(1, 0);
  std::vector<int> stack;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (!mask.data[i] || label[i]) continue;
      const int id = static_cast<int>(sizes->size());
      long long count = 0;
      label[i] = id;
      stack.assign(1, static_cast<int>(i));
      while (!stack.empty()) {
        const int p = stack.back();
        stack.pop_back();
        ++count;
        const int px = p % w, py = p / w;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int qx = px + dx, qy = py + dy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
            const size_t q = static_cast<size_t>(qy) * w + qx;
            if (mask.data[q] && !label[q]) {
              label[q] = id;
              stack.push_back(static_cast<int>(q));
            }
          }
        }
      }
      sizes->push_back(count);
    }
  }
  return label;
}

namespace {

// Erosion (set = false: a pixel stays only when its whole square is set) or dilation
// (set = true) with a (2r+1)^2 square, separably; outside the image counts as unset.
PixelMask SquareFilter(const PixelMask& in, int r, bool dilate) {
  PixelMask rows(in.width, in.height), out(in.width, in.height);
  auto pass = [&](const PixelMask& src, PixelMask* dst, bool horizontal) {
    for (int y = 0; y < src.height; ++y) {
      for (int x = 0; x < src.width; ++x) {
        bool any = false, all = true;
        for (int d = -r; d <= r; ++d) {
          const int qx = horizontal ? x + d : x, qy = horizontal ? y : y + d;
          const bool v = qx >= 0 && qy >= 0 && qx < src.width && qy < src.height && src.at(qx, qy);
          any = any || v;
          all = all && v;
        }
        dst->at(x, y) = (dilate ? any : all) ? 1 : 0;
      }
    }
  };
  pass(in, &rows, true);
  pass(rows, &out, false);
  return out;
}

// Background components (4-connected) below `max_pixels` not touching the border -> 1.
void FillHoles(PixelMask* mask, int max_pixels) {
  const int w = mask->width, h = mask->height;
  std::vector<uint8_t> seen(mask->data.size(), 0);
  std::vector<int> component, stack;
  for (size_t start = 0; start < mask->data.size(); ++start) {
    if (mask->data[start] || seen[start]) continue;
    component.clear();
    stack.assign(1, static_cast<int>(start));
    seen[start] = 1;
    bool border = false;
    while (!stack.empty()) {
      const int p = stack.back();
      stack.pop_back();
      component.push_back(p);
      const int px = p % w, py = p / w;
      if (px == 0 || py == 0 || px == w - 1 || py == h - 1) border = true;
      const int nx[4] = {px - 1, px + 1, px, px};
      const int ny[4] = {py, py, py - 1, py + 1};
      for (int k = 0; k < 4; ++k) {
        if (nx[k] < 0 || ny[k] < 0 || nx[k] >= w || ny[k] >= h) continue;
        const size_t q = static_cast<size_t>(ny[k]) * w + nx[k];
        if (!mask->data[q] && !seen[q]) {
          seen[q] = 1;
          stack.push_back(static_cast<int>(q));
        }
      }
    }
    if (!border && static_cast<long long>(component.size()) < max_pixels) {
      for (int p : component) mask->data[p] = 1;
    }
  }
}

}  // namespace

PixelMask ForegroundMask(const ImagePlanes& image, const ForegroundOptions& options) {
  options.Check();
  PixelMask mask(image.width, image.height);
  const int channels = std::max(1, image.channels);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      double sum = 0;
      for (int c = 0; c < channels; ++c) sum += image.at(c, x + image.x0, y + image.y0);
      mask.at(x, y) = sum / channels > options.background_max ? 1 : 0;
    }
  }
  if (options.open_radius > 0) {
    mask = SquareFilter(SquareFilter(mask, options.open_radius, false), options.open_radius, true);
  }
  if (options.largest_component || options.min_component_pixels > 0) KeepComponents(&mask, options);
  if (options.fill_holes_below > 0) FillHoles(&mask, options.fill_holes_below);
  return mask;
}

void KeepComponents(PixelMask* mask_in, const ForegroundOptions& options) {
  PixelMask& mask = *mask_in;
  std::vector<long long> sizes;
  const std::vector<int> label = LabelComponents(mask, &sizes);
  long long largest = 0;
  int largest_id = 0;
  for (size_t id = 1; id < sizes.size(); ++id) {
    if (sizes[id] > largest) {
      largest = sizes[id];
      largest_id = static_cast<int>(id);
    }
  }
  for (size_t i = 0; i < label.size(); ++i) {
    const int id = label[i];
    if (id == 0) continue;
    const bool keep = (!options.largest_component || id == largest_id) &&
                      sizes[id] >= options.min_component_pixels;
    mask.data[i] = keep ? 1 : 0;
  }
}

PixelMask CoverageMask(const TriangleScene& scene, const Camera& camera,
                       const Rigid3d& cam_from_world) {
  PixelMask mask(camera.width, camera.height);
  const PixelRays rays(camera, cam_from_world);
  tbb::parallel_for(tbb::blocked_range<int>(0, camera.height), [&](const auto& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y) {
      for (int x = 0; x < camera.width; ++x) {
        const RayHit hit = scene.Intersect(rays.origin(), rays.Direction(x, y));
        mask.at(x, y) = hit.hit ? 1 : 0;
      }
    }
  });
  return mask;
}

namespace {

// Squared distance transform along one line (Felzenszwalb and Huttenlocher): f holds
// 0 at the sites and a large value elsewhere; returns min_q (p - q)^2 + f(q).
void SquaredDistance1d(const std::vector<double>& f, std::vector<double>* d, std::vector<int>* v,
                       std::vector<double>* z) {
  const int n = static_cast<int>(f.size());
  d->assign(n, 0.0);
  v->assign(n, 0);
  z->assign(n + 1, 0.0);
  int k = 0;
  (*v)[0] = 0;
  (*z)[0] = -std::numeric_limits<double>::infinity();
  (*z)[1] = std::numeric_limits<double>::infinity();
  auto meet = [&](int q, int r) { return ((f[q] + double(q) * q) - (f[r] + double(r) * r)) / (2.0 * (q - r)); };
  for (int q = 1; q < n; ++q) {
    double s = meet(q, (*v)[k]);
    while (s <= (*z)[k]) {  // z[0] = -inf ends the loop
      --k;
      s = meet(q, (*v)[k]);
    }
    ++k;
    (*v)[k] = q;
    (*z)[k] = s;
    (*z)[k + 1] = std::numeric_limits<double>::infinity();
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while ((*z)[k + 1] < q) ++k;
    const int r = (*v)[k];
    (*d)[q] = double(q - r) * (q - r) + f[r];
  }
}

// Euclidean distance of every pixel centre to the nearest pixel with mask value `site`
// (a large value when there is none).
std::vector<double> DistanceTo(const PixelMask& mask, uint8_t site) {
  const int w = mask.width, h = mask.height;
  const double kFar = 1e20;
  std::vector<double> grid(static_cast<size_t>(w) * h);
  for (size_t i = 0; i < grid.size(); ++i) grid[i] = (mask.data[i] != 0) == (site != 0) ? 0.0 : kFar;
  std::vector<double> f, d, z;
  std::vector<int> v;
  for (int x = 0; x < w; ++x) {
    f.resize(h);
    for (int y = 0; y < h; ++y) f[y] = grid[static_cast<size_t>(y) * w + x];
    SquaredDistance1d(f, &d, &v, &z);
    for (int y = 0; y < h; ++y) grid[static_cast<size_t>(y) * w + x] = d[y];
  }
  for (int y = 0; y < h; ++y) {
    f.assign(grid.begin() + static_cast<size_t>(y) * w, grid.begin() + static_cast<size_t>(y + 1) * w);
    SquaredDistance1d(f, &d, &v, &z);
    for (int x = 0; x < w; ++x) grid[static_cast<size_t>(y) * w + x] = std::sqrt(d[x]);
  }
  return grid;
}

}  // namespace

SilhouetteDistance SignedDistanceToOutline(const PixelMask& mask) {
  SilhouetteDistance out;
  out.width = mask.width;
  out.height = mask.height;
  out.value.assign(mask.data.size(), 0.0f);
  if (mask.data.empty()) return out;
  const std::vector<double> to_inside = DistanceTo(mask, 1);
  const std::vector<double> to_outside = DistanceTo(mask, 0);
  const double cap = static_cast<double>(mask.width) + mask.height;  // no site at all
  for (size_t i = 0; i < mask.data.size(); ++i) {
    out.value[i] = static_cast<float>(mask.data[i] ? -(std::min(to_outside[i], cap) - 0.5)
                                                   : std::min(to_inside[i], cap) - 0.5);
  }
  return out;
}

bool SilhouetteDistance::Sample(const Eigen::Vector2d& position, double* distance,
                                Eigen::Vector2d* gradient) const {
  const double gx = position.x() - 0.5, gy = position.y() - 0.5;  // in pixel-centre units
  if (!(gx >= 0.0 && gy >= 0.0 && gx <= width - 1.0 && gy <= height - 1.0)) return false;
  const int x0 = std::min(static_cast<int>(gx), std::max(width - 2, 0));
  const int y0 = std::min(static_cast<int>(gy), std::max(height - 2, 0));
  const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
  const double fx = gx - x0, fy = gy - y0;
  const double v00 = at(x0, y0), v10 = at(x1, y0), v01 = at(x0, y1), v11 = at(x1, y1);
  *distance = (1 - fy) * ((1 - fx) * v00 + fx * v10) + fy * ((1 - fx) * v01 + fx * v11);
  if (gradient) {
    *gradient = Eigen::Vector2d((1 - fy) * (v10 - v00) + fy * (v11 - v01),
                                (1 - fx) * (v01 - v00) + fx * (v11 - v10));
  }
  return true;
}

MaskComparison CompareMasks(const PixelMask& foreground, const PixelMask& covered) {
  if (foreground.width != covered.width || foreground.height != covered.height) {
    throw std::invalid_argument("masks of different sizes: " + std::to_string(foreground.width) +
                                "x" + std::to_string(foreground.height) + " and " +
                                std::to_string(covered.width) + "x" +
                                std::to_string(covered.height));
  }
  MaskComparison c;
  for (size_t i = 0; i < foreground.data.size(); ++i) {
    const bool f = foreground.data[i] != 0, m = covered.data[i] != 0;
    c.foreground += f;
    c.covered += m;
    c.intersection += f && m;
    c.union_ += f || m;
  }
  return c;
}

void SummariseSilhouettes(SilhouetteReport* report) {
  if (report->images.empty()) return;
  std::vector<double> ious;
  double sum = 0;
  report->min_iou = 2.0;
  for (const SilhouetteImage& image : report->images) {
    const double iou = image.comparison.IoU();
    ious.push_back(iou);
    sum += iou;
    if (iou < report->min_iou) {
      report->min_iou = iou;
      report->worst_image = image.name;
    }
  }
  std::sort(ious.begin(), ious.end());
  const size_t n = ious.size();
  report->median_iou = n % 2 ? ious[n / 2] : 0.5 * (ious[n / 2 - 1] + ious[n / 2]);
  report->mean_iou = sum / static_cast<double>(n);
}

std::string SilhouetteReport::Table() const {
  std::ostringstream out;
  out << std::fixed;
  out << "  image                      foreground    mesh   both    IoU\n";
  for (const SilhouetteImage& image : images) {
    const MaskComparison& c = image.comparison;
    out << "  " << std::left << std::setw(24) << image.name << std::right << std::setw(12)
        << c.foreground << std::setw(8) << c.covered << std::setw(8) << c.intersection
        << std::setprecision(3) << std::setw(8) << c.IoU() << "\n";
  }
  out << std::setprecision(3) << "  IoU min " << min_iou << " (" << worst_image << "), median "
      << median_iou << ", mean " << mean_iou << ", " << images.size() << " images";
  return out.str();
}

std::string SilhouetteReport::Json() const {
  nlohmann::json j;
  j["iou_min"] = min_iou;
  j["iou_median"] = median_iou;
  j["iou_mean"] = mean_iou;
  j["worst_image"] = worst_image;
  nlohmann::json list = nlohmann::json::array();
  for (const SilhouetteImage& image : images) {
    const MaskComparison& c = image.comparison;
    list.push_back({{"name", image.name},
                    {"iou", c.IoU()},
                    {"foreground_pixels", c.foreground},
                    {"mesh_pixels", c.covered},
                    {"both_pixels", c.intersection},
                    {"either_pixels", c.union_}});
  }
  j["images"] = list;
  return j.dump(2);
}

namespace {

void WriteComparisonImage(const std::string& path, const PixelMask& foreground,
                          const PixelMask& covered) {
  ImagePlanes out;
  out.width = foreground.width;
  out.height = foreground.height;
  out.channels = 1;
  out.data.resize(foreground.data.size());
  for (size_t i = 0; i < out.data.size(); ++i) {
    const bool f = foreground.data[i] != 0, m = covered.data[i] != 0;
    out.data[i] = f && m ? 255.0f : f ? 170.0f : m ? 85.0f : 0.0f;
  }
  WriteImage(path, out, 8);
}

}  // namespace

SilhouetteReport EvaluateSilhouettes(const ImageBlock& block,
                                     const std::vector<Eigen::Vector3d>& vertices,
                                     const std::vector<Eigen::Vector3i>& triangles,
                                     const ForegroundOptions& options,
                                     const std::string& mask_dir) {
  options.Check();
  if (triangles.empty()) throw std::invalid_argument("the mesh has no triangles");
  const TriangleScene scene(EmbreeDevice::Shared(), vertices, triangles);
  if (!mask_dir.empty()) std::filesystem::create_directories(mask_dir);
  SilhouetteReport report;
  for (const BlockImage& image : block.images) {
    if (image.path.empty()) {
      throw std::runtime_error("image " + image.name + ": no file (give the image folder)");
    }
    const Camera& camera = block.CameraOf(image);
    PixelMask foreground;
    try {
      foreground = ForegroundMask(ReadImageFor(image.path, camera), options);
    } catch (const std::exception& e) {
      throw std::runtime_error(image.path + ": " + e.what());
    }
    const PixelMask covered = CoverageMask(scene, camera, image.cam_from_world);
    report.images.push_back({image.name, CompareMasks(foreground, covered)});
    if (!mask_dir.empty()) {
      std::string stem = std::filesystem::path(image.name).stem().string();
      WriteComparisonImage((std::filesystem::path(mask_dir) / (stem + ".png")).string(),
                           foreground, covered);
    }
  }
  SummariseSilhouettes(&report);
  return report;
}

}  // namespace facets
