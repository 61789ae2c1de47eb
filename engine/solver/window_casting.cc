// WindowAdjustment: the observations of one iteration. Every pixel of the 8x8 blocks the
// window's faces project to is cast into the window's tessellation (first hit only);
// background pixels are dropped; the grey values start from the pixels that see each
// node; an image counts as a view of a vertex when it sees enough of its faces.
#include "engine/solver/window_adjustment.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "visibility/image_selection.h"
#include "visibility/occluder_selection.h"
#include "visibility/surface_scene.h"

namespace facets {

void WindowAdjustment::RefreshOccluders(const std::vector<Eigen::AlignedBox3d>& face_boxes) {
  if (!occluder_source_) return;
  std::shared_ptr<const OccluderScene> occluders = occluder_source_(face_boxes);
  if (occluders == occluders_) return;
  occluders_ = std::move(occluders);
  scene_->SetOccluders(occluders_);
  ++clocks_.occluder_scenes;
}

long long WindowAdjustment::CastAll(const std::vector<Eigen::AlignedBox3d>& face_boxes,
                                    std::vector<std::vector<PixelObservation>>* casts, IterationReport* it) {
  Eigen::AlignedBox3d box;
  for (const auto& p : tess_.points) box.extend(p);
  // Only the 8x8 pixel blocks onto which some face of the window projects (face_boxes:
  // FaceBoxes(tess_)): the rest of the window's rectangle sees the surroundings only.
  CastOptions cast_options;
  cast_options.min_cos_incidence = options_.min_cos_incidence;
  casts->assign(images_.size(), {});
  std::vector<long long> image_rays(images_.size(), 0), image_rect(images_.size(), 0);
  tbb::parallel_for(size_t{0}, images_.size(), [&](size_t k) {
    const auto rect = ProjectBox(box, *images_[k].camera, images_[k].cam_from_world);
    if (!rect) return;
    // Only pixels the window was given (a region of the image when read per window).
    const ImagePlanes& pixels = *images_[k].pixels;
    const PixelRect held{pixels.x0, pixels.y0, pixels.x0 + pixels.width, pixels.y0 + pixels.height};
    const PixelRect cast = rect->Intersection(held);
    if (cast.Empty()) return;
    image_rect[k] = cast.Area();
    const std::vector<PixelRect> blocks =
        ProjectedBlocks(face_boxes, *images_[k].camera, images_[k].cam_from_world, cast);
    CastResult result = CastPixels(*scene_, *images_[k].camera, images_[k].cam_from_world, blocks, cast_options);
    image_rays[k] = result.stats.rays;
    (*casts)[k] = std::move(result.observations);
  });
  it->rays = it->rect_pixels = 0;
  for (size_t k = 0; k < images_.size(); ++k) {
    it->rays += image_rays[k];
    it->rect_pixels += image_rect[k];
  }
  long long total = 0;
  for (const auto& list : *casts) total += static_cast<long long>(list.size());
  return total;
}

long long WindowAdjustment::DropBackground(std::vector<std::vector<PixelObservation>>* casts) const {
  if (options_.background_below < 0.0) return 0;
  long long dropped = 0;
  for (size_t k = 0; k < casts->size(); ++k) {
    const ImagePlanes& pixels = *images_[k].pixels;
    auto& list = (*casts)[k];
    const size_t before = list.size();
    list.erase(std::remove_if(list.begin(), list.end(),
                              [&](const PixelObservation& obs) {
                                double sum = 0.0;
                                for (int c = 0; c < channels_; ++c) sum += pixels.at(c, obs.x, obs.y);
                                return sum / channels_ <= options_.background_below;
                              }),
               list.end());
    dropped += static_cast<long long>(before - list.size());
  }
  return dropped;
}

double WindowAdjustment::RobustScale(const std::vector<std::vector<PixelObservation>>& casts) const {
  std::vector<float> residuals;
  for (size_t k = 0; k < casts.size(); ++k) {
    const ImagePlanes& pixels = *images_[k].pixels;
    for (const PixelObservation& obs : casts[k]) {
      const Eigen::Vector3i& tri = tess_.triangles[obs.facet];
      for (int c = 0; c < channels_; ++c) {
        const double object = (1.0 - obs.u - obs.v) * grey_[tri[0] * channels_ + c] +
                              obs.u * grey_[tri[1] * channels_ + c] + obs.v * grey_[tri[2] * channels_ + c];
        const auto& rad = radiometry_[k][c];
        const double predicted = (object - rad[0]) / rad[1];
        residuals.push_back(static_cast<float>(std::abs(pixels.at(c, obs.x, obs.y) - predicted)));
      }
    }
  }
  if (residuals.empty()) return 0.0;
  auto middle = residuals.begin() + residuals.size() / 2;
  std::nth_element(residuals.begin(), middle, residuals.end());
  return 1.4826 * *middle;
}

void WindowAdjustment::InitialiseGrey(const std::vector<std::vector<PixelObservation>>& casts) {
  const size_t num_nodes = tess_.points.size();
  std::vector<double> sum(num_nodes * channels_, 0.0), weight(num_nodes, 0.0);
  double total = 0.0;
  long long count = 0;
  for (size_t k = 0; k < casts.size(); ++k) {
    const ImagePlanes& pixels = *images_[k].pixels;
    for (const PixelObservation& obs : casts[k]) {
      const Eigen::Vector3i& tri = tess_.triangles[obs.facet];
      const double w[3] = {1.0 - obs.u - obs.v, obs.u, obs.v};
      for (int corner = 0; corner < 3; ++corner) {
        weight[tri[corner]] += w[corner];
        for (int c = 0; c < channels_; ++c) {
          const double g = pixels.at(c, obs.x, obs.y);
          const auto& rad = radiometry_[k][c];
          sum[tri[corner] * channels_ + c] += w[corner] * (g * rad[1] + rad[0]);
        }
      }
      for (int c = 0; c < channels_; ++c) {
        total += pixels.at(c, obs.x, obs.y);
      }
      ++count;
    }
  }
  const double mean = count > 0 ? total / (count * channels_) : 0.0;
  grey_.assign(num_nodes * channels_, mean);
  for (size_t n = 0; n < num_nodes; ++n) {
    if (weight[n] <= 1e-9) continue;
    for (int c = 0; c < channels_; ++c) grey_[n * channels_ + c] = sum[n * channels_ + c] / weight[n];
  }
}

std::vector<int> WindowAdjustment::VertexViews(const std::vector<std::vector<PixelObservation>>& casts) const {
  // An image counts as a view of a vertex when its pixels on the faces around the vertex
  // are at least min_view_share of the best image's: a wall 3-7 degrees off a nadir
  // image's rays shows 1-2 pixels of its height there, which pins nothing down.
  const size_t num_images = images_.size();
  std::vector<int> face_pixels(face_vertices_.size() * num_images, 0);
  for (size_t k = 0; k < casts.size(); ++k) {
    for (const PixelObservation& obs : casts[k]) ++face_pixels[static_cast<size_t>(obs.face) * num_images + k];
  }
  std::vector<int> views(mesh_->n_vertices(), 0);
  std::vector<int> pixels(num_images);
  for (auto vh : mesh_->vertices()) {
    std::fill(pixels.begin(), pixels.end(), 0);
    for (auto fh : mesh_->vf_range(vh)) {
      for (size_t k = 0; k < num_images; ++k) pixels[k] += face_pixels[static_cast<size_t>(fh.idx()) * num_images + k];
    }
    const int best = *std::max_element(pixels.begin(), pixels.end());
    for (size_t k = 0; k < num_images; ++k) {
      if (pixels[k] > 0 && pixels[k] >= options_.min_view_share * best) ++views[vh.idx()];
    }
  }
  return views;
}

}  // namespace facets
