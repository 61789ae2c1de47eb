// Held-out views: rendering a held-out camera from the other images (scenes/holdout.h).
#include "scenes/holdout.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "visibility/embree_scene.h"
#include "visibility/pixel_cast.h"

namespace facets {
namespace {

// Bilinear grey value between pixel centres (centre of pixel (x, y) at (x + 0.5, y + 0.5));
// false when the position lies outside the span of the centres.
bool SampleBilinear(const ImagePlanes& grey, const Eigen::Vector2d& position, double* value) {
  const double fx = position.x() - 0.5, fy = position.y() - 0.5;
  if (!(fx >= 0.0 && fy >= 0.0 && fx <= grey.width - 1 && fy <= grey.height - 1)) return false;
  const int x = std::min(static_cast<int>(fx), grey.width - 2 < 0 ? 0 : grey.width - 2);
  const int y = std::min(static_cast<int>(fy), grey.height - 2 < 0 ? 0 : grey.height - 2);
  const double ax = fx - x, ay = fy - y;
  const int x1 = std::min(x + 1, grey.width - 1), y1 = std::min(y + 1, grey.height - 1);
  *value = (1 - ay) * ((1 - ax) * grey.at(0, x, y) + ax * grey.at(0, x1, y)) +
           ay * ((1 - ax) * grey.at(0, x, y1) + ax * grey.at(0, x1, y1));
  return true;
}

// The images' weighted mean grey value at `point` (unit `normal` facing the viewer), over
// the source images that see it; NaN when none does.
double ColourFromImages(const TriangleScene& scene, const ImageBlock& block, const Eigen::Vector3d& point,
                        const Eigen::Vector3d& normal, const std::vector<int>& sources,
                        const std::vector<ImagePlanes>& greys, double min_cos) {
  double sum = 0.0, weights = 0.0;
  for (int source : sources) {
    const BlockImage& image = block.images[source];
    const Eigen::Vector3d in_camera = image.cam_from_world * point;
    if (in_camera.z() <= 0.0) continue;
    const Eigen::Vector3d to_centre = image.ProjectionCentre() - point;
    const double distance = to_centre.norm();
    const double cos_incidence = normal.dot(to_centre) / distance;
    if (cos_incidence < min_cos) continue;
    double grey = 0.0;
    if (!SampleBilinear(greys[source], block.CameraOf(image).ImageFromCam(in_camera), &grey)) continue;
    // The ray to the projection centre starts a 1e-4 of the distance off the surface, so
    // the point's own triangle does not stop it; t is in units of to_centre.
    const Eigen::Vector3d start = point + normal * (1e-4 * distance);
    if (scene.Occluded(start, to_centre, 1e-4f, 1.0f)) continue;
    sum += cos_incidence * grey;
    weights += cos_incidence;
  }
  return weights > 0.0 ? sum / weights : kNoValue;
}

void WriteRendering(const std::string& dir, const std::string& name, const ImagePlanes& rendered) {
  std::filesystem::create_directories(dir);
  ImagePlanes image = rendered;
  for (float& value : image.data) value = std::isfinite(value) ? value : 0.0f;
  const std::string stem = std::filesystem::path(name).stem().string();
  WriteImage((std::filesystem::path(dir) / (stem + "_holdout.png")).string(), image);
}

}  // namespace

void HoldoutOptions::Check() const {
  if (window < 3 || window % 2 == 0) throw std::invalid_argument("holdout window must be odd and >= 3");
  if (!(min_window_std >= 0.0)) throw std::invalid_argument("holdout min window std must be >= 0");
  if (!(min_cos_incidence >= 0.0 && min_cos_incidence < 1.0)) {
    throw std::invalid_argument("holdout min cos incidence must lie in [0, 1)");
  }
  if (foreground) foreground->Check();
}

ImagePlanes RenderFromImages(const TriangleScene& scene, const ImageBlock& block, int held_out,
                             const std::vector<int>& sources, const std::vector<ImagePlanes>& greys,
                             const HoldoutOptions& options) {
  const BlockImage& image = block.images.at(held_out);
  const Camera& camera = block.CameraOf(image);
  ImagePlanes rendered;
  rendered.width = camera.width;
  rendered.height = camera.height;
  rendered.channels = 1;
  rendered.data.assign(static_cast<size_t>(camera.width) * camera.height, std::nanf(""));
  const PixelRays rays(camera, image.cam_from_world);
  tbb::parallel_for(tbb::blocked_range<int>(0, camera.height), [&](const auto& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y) {
      for (int x = 0; x < camera.width; ++x) {
        const Eigen::Vector3d direction = rays.Direction(x, y);
        const RayHit hit = scene.Intersect(rays.origin(), direction);
        if (!hit.hit) continue;
        const Eigen::Vector3d point = rays.origin() + direction * static_cast<double>(hit.distance);
        if (options.roi && !options.roi->Contains(point)) continue;
        Eigen::Vector3d normal = hit.geom_normal.cast<double>().normalized();
        if (normal.dot(direction) > 0.0) normal = -normal;  // the side the held-out camera sees
        rendered.at(0, x, y) = static_cast<float>(
            ColourFromImages(scene, block, point, normal, sources, greys, options.min_cos_incidence));
      }
    }
  });
  return rendered;
}

HoldoutReport EvaluateHoldout(const ImageBlock& block, const std::vector<Eigen::Vector3d>& vertices,
                              const std::vector<Eigen::Vector3i>& triangles,
                              const HoldoutOptions& options) {
  options.Check();
  const std::vector<int> held_out = SelectImages(block, options.images);
  if (held_out.empty()) {
    throw std::invalid_argument("held-out selection " + options.images + " names no image of the " +
                                std::to_string(block.images.size()));
  }
  std::vector<int> sources;
  for (int i = 0; i < static_cast<int>(block.images.size()); ++i) {
    if (!std::binary_search(held_out.begin(), held_out.end(), i)) sources.push_back(i);
  }
  if (sources.empty()) throw std::invalid_argument("held-out selection " + options.images + " names every image");
  std::vector<ImagePlanes> greys(block.images.size());
  for (size_t i = 0; i < block.images.size(); ++i) {
    greys[i] = ReadImageFor(block.images[i].path, block.CameraOf(block.images[i])).Grey();
  }
  const TriangleScene scene(EmbreeDevice::Shared(), vertices, triangles);
  HoldoutReport report;
  for (int index : held_out) {
    const BlockImage& image = block.images[index];
    const ImagePlanes rendered = RenderFromImages(scene, block, index, sources, greys, options);
    if (!options.render_dir.empty()) WriteRendering(options.render_dir, image.name, rendered);
    PixelMask object;
    if (options.foreground) object = ForegroundMask(ReadImage(image.path), *options.foreground);
    report.images.push_back(ScoreHoldoutImage(image.name, greys[index], rendered, options,
                                              options.foreground ? &object : nullptr));
  }
  SummariseHoldout(&report);
  return report;
}

}  // namespace facets
