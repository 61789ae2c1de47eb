#include "visibility/pixel_cast.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace facets {
namespace {

constexpr int kPacket = 16;

// (b1, b2) of the three corners of each local sub-triangle, as float for the
// per-hit mapping.
struct CornerTable {
  float b[kSubTrianglesPerFace][3][2];
  CornerTable() {
    for (int k = 0; k < kSubTrianglesPerFace; ++k) {
      const auto& corners = SubTriangleCorners(k);
      for (int c = 0; c < 3; ++c) {
        b[k][c][0] = static_cast<float>(corners[c][1]);
        b[k][c][1] = static_cast<float>(corners[c][2]);
      }
    }
  }
};

const CornerTable& Corners() {
  static const CornerTable table;
  return table;
}

void Accumulate(const CastStats& add, CastStats* total) {
  total->rays += add.rays;
  total->observations += add.observations;
  total->misses += add.misses;
  total->back_faces += add.back_faces;
  total->grazing += add.grazing;
  total->occluded += add.occluded;
}

// Casts up to 16 rays (pixels xs[i], ys[i], i < n) as one packet. Writes one entry per
// ray when keep_invalid, else only observations, to `out`; returns the count written.
int CastPacket(RTCScene scene, const PixelRays& rays, const int* xs, const int* ys,
               int n, const CastOptions& options, const CornerTable& corners,
               PixelObservation* out, CastStats* stats) {
  alignas(64) RTCRayHit16 packet;
  alignas(64) int valid[kPacket];
  const Eigen::Vector3d& origin = rays.origin();
  for (int i = 0; i < kPacket; ++i) {
    valid[i] = i < n ? -1 : 0;
    Eigen::Vector3d direction(0, 0, 1);
    if (i < n) direction = rays.Direction(xs[i], ys[i]);
    SetPacketRay(&packet, i, origin, direction);
  }
  IntersectCoherent16(valid, scene, &packet);

  const float min_cos = static_cast<float>(options.min_cos_incidence);
  int written = 0;
  stats->rays += n;
  for (int i = 0; i < n; ++i) {
    PixelObservation obs;
    obs.x = xs[i];
    obs.y = ys[i];
    if (packet.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) {
      ++stats->misses;
      if (options.keep_invalid) out[written++] = obs;
      continue;
    }
    // Occluders are an instance (TriangleScene::SetOccluders): hit.instID set.
    if (packet.hit.instID[0][i] != RTC_INVALID_GEOMETRY_ID || packet.hit.geomID[i] != 0) {
      obs.status = RayStatus::kOccluded;
      ++stats->occluded;
      if (options.keep_invalid) out[written++] = obs;
      continue;
    }
    const float dx = packet.ray.dir_x[i], dy = packet.ray.dir_y[i],
                dz = packet.ray.dir_z[i];
    const float nx = packet.hit.Ng_x[i], ny = packet.hit.Ng_y[i], nz = packet.hit.Ng_z[i];
    // Ng = (V1-V0) x (V2-V0): the counter-clockwise (outside) normal.
    const float dot = dx * nx + dy * ny + dz * nz;
    const float norm = std::sqrt(nx * nx + ny * ny + nz * nz);
    const float cos_incidence = norm > 0 ? std::fabs(dot) / norm : 0.0f;
    if (options.cull_back_faces && dot > 0) {
      obs.status = RayStatus::kBackFace;
      ++stats->back_faces;
    } else if (!(cos_incidence >= min_cos)) {
      obs.status = RayStatus::kGrazing;
      ++stats->grazing;
    } else {
      obs.status = RayStatus::kObservation;
      ++stats->observations;
    }
    if (obs.status != RayStatus::kObservation && !options.keep_invalid) continue;
    const unsigned facet = packet.hit.primID[i];
    const float u = packet.hit.u[i], v = packet.hit.v[i], w = 1.0f - u - v;
    const auto& c = corners.b[facet % kSubTrianglesPerFace];
    obs.facet = static_cast<int32_t>(facet);
    obs.face = static_cast<int32_t>(facet / kSubTrianglesPerFace);
    obs.u = u;
    obs.v = v;
    obs.b1 = w * c[0][0] + u * c[1][0] + v * c[2][0];
    obs.b2 = w * c[0][1] + u * c[1][1] + v * c[2][1];
    obs.distance = packet.ray.tfar[i];
    obs.cos_incidence = cos_incidence;
    out[written++] = obs;
  }
  return written;
}

// Moves the per-task chunks (written at offsets[t], counts[t] long) together.
void Compact(const std::vector<long long>& offsets, const std::vector<long long>& counts,
             std::vector<PixelObservation>* observations) {
  long long end = 0;
  for (size_t t = 0; t < counts.size(); ++t) {
    if (offsets[t] != end) {
      std::copy(observations->begin() + offsets[t],
                observations->begin() + offsets[t] + counts[t],
                observations->begin() + end);
    }
    end += counts[t];
  }
  observations->resize(end);
}

}  // namespace

PixelRect PixelRect::Intersection(const PixelRect& other) const {
  PixelRect r{std::max(x0, other.x0), std::max(y0, other.y0), std::min(x1, other.x1),
              std::min(y1, other.y1)};
  if (r.Empty()) return {};
  return r;
}

void CastOptions::Check() const {
  if (!(min_cos_incidence >= 0.0 && min_cos_incidence <= 1.0)) {
    throw std::invalid_argument("CastOptions: min_cos_incidence must be in [0, 1], is " +
                                std::to_string(min_cos_incidence));
  }
  if (tile_size < 4 || tile_size % 4 != 0) {
    throw std::invalid_argument("CastOptions: tile_size must be a positive multiple of 4, is " +
                                std::to_string(tile_size));
  }
}

PixelRays::PixelRays(const Camera& camera, const Rigid3d& cam_from_world)
    : camera_(camera) {
  camera.Check();
  if (!cam_from_world.rotation.coeffs().allFinite() ||
      !cam_from_world.translation.allFinite()) {
    throw std::invalid_argument("PixelRays: pose of camera " +
                                std::to_string(camera.camera_id) + " is not finite");
  }
  distorted_ = camera.HasDistortion();
  world_from_cam_ = cam_from_world.rotation.conjugate().toRotationMatrix();
  Eigen::Matrix3d cam_from_pixel = Eigen::Matrix3d::Identity();
  cam_from_pixel(0, 0) = 1.0 / camera.FocalX();
  cam_from_pixel(1, 1) = 1.0 / camera.FocalY();
  cam_from_pixel(0, 2) = -camera.PrincipalX() / camera.FocalX();
  cam_from_pixel(1, 2) = -camera.PrincipalY() / camera.FocalY();
  world_from_pixel_ = world_from_cam_ * cam_from_pixel;
  origin_ = -(world_from_cam_ * cam_from_world.translation);
}

Eigen::Vector3d PixelRays::Direction(int x, int y) const {
  Eigen::Vector3d direction;
  if (distorted_) {
    direction = world_from_cam_ * camera_.CamFromImage(Eigen::Vector2d(x + 0.5, y + 0.5));
  } else {
    direction = world_from_pixel_ * Eigen::Vector3d(x + 0.5, y + 0.5, 1.0);
  }
  return direction.normalized();
}

namespace {

// First hits for the pixels of num_tiles rectangles tile_rect(t) (each inside the
// image), in tile order, 4x4 packets within a tile, tiles spread over TBB.
template <typename TileRect>
CastResult CastTiles(const SurfaceScene& scene, const PixelRays& rays, int num_tiles,
                     const TileRect& tile_rect, const CastOptions& options) {
  CastResult result;
  std::vector<long long> offsets(num_tiles), counts(num_tiles, 0);
  long long total = 0;
  for (int t = 0; t < num_tiles; ++t) {
    offsets[t] = total;
    total += tile_rect(t).Area();
  }
  result.observations.resize(total);
  std::vector<CastStats> tile_stats(num_tiles);
  const CornerTable& corners = Corners();
  const RTCScene rtc_scene = scene.get();
  tbb::parallel_for(tbb::blocked_range<int>(0, num_tiles, 1), [&](const auto& range) {
    int xs[kPacket], ys[kPacket];
    for (int t = range.begin(); t < range.end(); ++t) {
      const PixelRect tile = tile_rect(t);
      PixelObservation* out = result.observations.data() + offsets[t];
      long long written = 0;
      for (int by = tile.y0; by < tile.y1; by += 4) {
        for (int bx = tile.x0; bx < tile.x1; bx += 4) {
          int n = 0;
          for (int y = by; y < std::min(by + 4, tile.y1); ++y) {
            for (int x = bx; x < std::min(bx + 4, tile.x1); ++x) {
              xs[n] = x;
              ys[n] = y;
              ++n;
            }
          }
          written += CastPacket(rtc_scene, rays, xs, ys, n, options, corners,
                                out + written, &tile_stats[t]);
        }
      }
      counts[t] = written;
    }
  });
  scene.device().Check();
  Compact(offsets, counts, &result.observations);
  for (const CastStats& s : tile_stats) Accumulate(s, &result.stats);
  return result;
}

}  // namespace

CastResult CastPixels(const SurfaceScene& scene, const Camera& camera,
                      const Rigid3d& cam_from_world, const PixelRect& rect_in,
                      const CastOptions& options) {
  options.Check();
  const PixelRays rays(camera, cam_from_world);
  const PixelRect rect = rect_in.Intersection(PixelRect::Full(camera));
  if (rect.Empty()) return {};
  const int ts = options.tile_size;
  const int tiles_x = (rect.Width() + ts - 1) / ts;
  const int tiles_y = (rect.Height() + ts - 1) / ts;
  auto tile_rect = [&](int t) {
    const int tx = t % tiles_x, ty = t / tiles_x;
    return PixelRect{rect.x0 + tx * ts, rect.y0 + ty * ts,
                     std::min(rect.x1, rect.x0 + (tx + 1) * ts),
                     std::min(rect.y1, rect.y0 + (ty + 1) * ts)};
  };
  return CastTiles(scene, rays, tiles_x * tiles_y, tile_rect, options);
}

CastResult CastPixels(const SurfaceScene& scene, const Camera& camera,
                      const Rigid3d& cam_from_world, const std::vector<PixelRect>& rects_in,
                      const CastOptions& options) {
  options.Check();
  const PixelRays rays(camera, cam_from_world);
  const PixelRect full = PixelRect::Full(camera);
  std::vector<PixelRect> rects;
  rects.reserve(rects_in.size());
  for (const PixelRect& r : rects_in) {
    const PixelRect clipped = r.Intersection(full);
    if (!clipped.Empty()) rects.push_back(clipped);
  }
  return CastTiles(scene, rays, static_cast<int>(rects.size()), [&](int t) { return rects[t]; }, options);
}

CastResult CastPixels(const SurfaceScene& scene, const Camera& camera,
                      const Rigid3d& cam_from_world,
                      const std::vector<Eigen::Vector2i>& pixels_in,
                      const CastOptions& options) {
  options.Check();
  const PixelRays rays(camera, cam_from_world);
  std::vector<Eigen::Vector2i> pixels;
  pixels.reserve(pixels_in.size());
  const PixelRect full = PixelRect::Full(camera);
  for (const Eigen::Vector2i& p : pixels_in) {
    if (full.Contains(p.x(), p.y())) pixels.push_back(p);
  }
  CastResult result;
  constexpr long long kChunk = 1024;  // pixels per task, a multiple of kPacket
  const long long num_pixels = static_cast<long long>(pixels.size());
  const int num_chunks = static_cast<int>((num_pixels + kChunk - 1) / kChunk);
  std::vector<long long> offsets(num_chunks), counts(num_chunks, 0);
  for (int c = 0; c < num_chunks; ++c) offsets[c] = c * kChunk;
  result.observations.resize(num_pixels);
  std::vector<CastStats> chunk_stats(num_chunks);
  const CornerTable& corners = Corners();
  const RTCScene rtc_scene = scene.get();
  tbb::parallel_for(tbb::blocked_range<int>(0, num_chunks, 1), [&](const auto& range) {
    int xs[kPacket], ys[kPacket];
    for (int c = range.begin(); c < range.end(); ++c) {
      const long long begin = c * kChunk;
      const long long end = std::min(num_pixels, begin + kChunk);
      long long written = 0;
      for (long long p = begin; p < end; p += kPacket) {
        const int n = static_cast<int>(std::min<long long>(kPacket, end - p));
        for (int i = 0; i < n; ++i) {
          xs[i] = pixels[p + i].x();
          ys[i] = pixels[p + i].y();
        }
        written += CastPacket(rtc_scene, rays, xs, ys, n, options, corners,
                              result.observations.data() + begin + written,
                              &chunk_stats[c]);
      }
      counts[c] = written;
    }
  });
  scene.device().Check();
  Compact(offsets, counts, &result.observations);
  for (const CastStats& s : chunk_stats) Accumulate(s, &result.stats);
  return result;
}

CastResult CastPixels(const SurfaceScene& scene, const ImageBlock& block, int image_index,
                      const PixelRect& rect, const CastOptions& options) {
  if (image_index < 0 || image_index >= static_cast<int>(block.images.size())) {
    throw std::out_of_range("CastPixels: image index " + std::to_string(image_index) +
                            " out of range");
  }
  const BlockImage& image = block.images[image_index];
  return CastPixels(scene, block.CameraOf(image), image.cam_from_world, rect, options);
}

}  // namespace facets
