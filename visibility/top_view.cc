#include "visibility/top_view.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace facets {

void TopViewOptions::Check() const {
  if (!(start_margin > 0.0) || !std::isfinite(start_margin)) {
    throw std::invalid_argument("TopViewOptions: start_margin must be positive and finite");
  }
}

namespace {

constexpr int kPacket = 16;
// Each back face skipped costs one more single ray; a real surface has at most a few
// layers under a pixel, so this only guards against pathological input.
constexpr int kMaxBackFaceSkips = 64;

struct Hit {
  int32_t facet = -1;
  float u = 0, v = 0;
  double z = std::numeric_limits<double>::quiet_NaN();
  bool back_face = false;
};

// Exact hit of the vertical line through xy with facet s, in double: the 2D
// barycentrics of xy in the facet's XY projection give u, v, and z follows from them
// (for a planar facet that is the exact intersection). A (near-)vertical facet has no
// usable projection; there Embree's float barycentrics are kept.
Hit ResolveHit(const Tessellation& tess, int s, const Eigen::Vector2d& xy, float eu, float ev) {
  const Eigen::Vector3i& t = tess.triangles[s];
  const Eigen::Vector3d& p0 = tess.points[t[0]];
  const Eigen::Vector3d& p1 = tess.points[t[1]];
  const Eigen::Vector3d& p2 = tess.points[t[2]];
  const Eigen::Vector2d e1 = (p1 - p0).head<2>(), e2 = (p2 - p0).head<2>();
  const Eigen::Vector2d q = xy - p0.head<2>();
  const double det = e1.x() * e2.y() - e1.y() * e2.x();  // = 2 * projected area * sign
  const double scale = (p1 - p0).norm() * (p2 - p0).norm();
  Hit hit;
  hit.facet = s;
  double u = eu, v = ev;
  if (std::abs(det) > 1e-9 * scale) {
    u = (q.x() * e2.y() - q.y() * e2.x()) / det;
    v = (e1.x() * q.y() - e1.y() * q.x()) / det;
    // Embree decided the facet in float; keep the double barycentrics inside it.
    u = std::clamp(u, 0.0, 1.0);
    v = std::clamp(v, 0.0, 1.0);
    if (u + v > 1.0) {
      const double sum = u + v;
      u /= sum;
      v /= sum;
    }
  }
  // The facet normal's Z has the sign of det (triangles are counter-clockwise seen
  // from the side the normal points to).
  hit.back_face = det < -1e-9 * scale;
  hit.u = static_cast<float>(u);
  hit.v = static_cast<float>(v);
  hit.z = (1.0 - u - v) * p0.z() + u * p1.z() + v * p2.z();
  return hit;
}

// Continues a ray that first hit a back face just below each back face it meets
// (from the ray's parameter t, float, down to t_far) until it hits a front face: true
// with that face's hit in *hit, false when it leaves the surface or meets more than
// kMaxBackFaceSkips back faces.
bool FrontHitBelow(RTCScene rtc_scene, const Tessellation& tessellation, const Eigen::Vector2d& xy, float org_x,
                   float org_y, float org_z, float t, float t_far, Hit* hit) {
  for (int k = 0; k < kMaxBackFaceSkips; ++k) {
    RTCRayHit single;
    single.ray.org_x = org_x;
    single.ray.org_y = org_y;
    single.ray.org_z = org_z;
    single.ray.dir_x = 0.0f;
    single.ray.dir_y = 0.0f;
    single.ray.dir_z = -1.0f;
    // The next float after t, plus a micrometre-scale step: a facet sharing
    // the back face's edge is not found twice.
    single.ray.tnear = std::nextafter(t, t_far) + 1e-6f * std::max(1.0f, t);
    single.ray.tfar = t_far;
    single.ray.time = 0.0f;
    single.ray.mask = 0xFFFFFFFFu;
    single.ray.id = 0;
    single.ray.flags = 0;
    single.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    single.hit.primID = RTC_INVALID_GEOMETRY_ID;
    single.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    RTCIntersectContext single_context;
    rtcInitIntersectContext(&single_context);
    rtcIntersect1(rtc_scene, &single_context, &single);
    if (single.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    t = single.ray.tfar;
    *hit = ResolveHit(tessellation, static_cast<int>(single.hit.primID), xy, single.hit.u, single.hit.v);
    if (!hit->back_face) return true;
  }
  return false;
}

// The vertical rays of one row of the grid, cast from height z_start down to t_far
// below it in packets of kPacket: the first hits go into *top, counts into *stats.
void CastRow(RTCScene rtc_scene, const Tessellation& tessellation, const TopViewOptions& options, int row,
             double z_start, float t_far, TopView* top, TopViewStats* stats) {
  const RasterGrid& grid = top->grid;
  alignas(64) RTCRayHit16 packet;
  alignas(64) int valid[kPacket];
  for (int col0 = 0; col0 < grid.width; col0 += kPacket) {
    const int count = std::min(kPacket, grid.width - col0);
    for (int i = 0; i < kPacket; ++i) {
      valid[i] = i < count ? -1 : 0;
      const Eigen::Vector2d xy = grid.PixelCentre(col0 + std::min(i, count - 1), row);
      SetPacketRay(&packet, i, Eigen::Vector3d(xy.x(), xy.y(), z_start), Eigen::Vector3d(0, 0, -1), t_far);
    }
    IntersectCoherent16(valid, rtc_scene, &packet);

    for (int i = 0; i < count; ++i) {
      const int col = col0 + i;
      const Eigen::Vector2d xy = grid.PixelCentre(col, row);
      if (packet.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) {
        ++stats->misses;
        continue;
      }
      Hit hit = ResolveHit(tessellation, static_cast<int>(packet.hit.primID[i]), xy, packet.hit.u[i], packet.hit.v[i]);
      if (hit.back_face) ++stats->back_faces;
      if (hit.back_face && options.skip_back_faces &&
          !FrontHitBelow(rtc_scene, tessellation, xy, packet.ray.org_x[i], packet.ray.org_y[i], packet.ray.org_z[i],
                         packet.ray.tfar[i], t_far, &hit)) {
        ++stats->misses;
        continue;
      }
      const size_t idx = top->Index(col, row);
      top->facet[idx] = hit.facet;
      top->u[idx] = hit.u;
      top->v[idx] = hit.v;
      top->z[idx] = hit.z;
      ++stats->hits;
    }
  }
}

}  // namespace

TopView CastTopView(const SurfaceScene& scene, const Tessellation& tessellation,
                    const RasterGrid& grid, const TopViewOptions& options) {
  options.Check();
  grid.Check();
  if (scene.NumFacets() != static_cast<int>(tessellation.triangles.size()) ||
      scene.NumPoints() != static_cast<int>(tessellation.points.size())) {
    throw std::invalid_argument("CastTopView: the scene (" + std::to_string(scene.NumFacets()) +
                                " facets) was not built from this tessellation (" +
                                std::to_string(tessellation.triangles.size()) + " facets)");
  }
  TopView top;
  top.grid = grid;
  const size_t n = static_cast<size_t>(grid.NumPixels());
  top.facet.assign(n, -1);
  top.u.assign(n, 0.0f);
  top.v.assign(n, 0.0f);
  top.z.assign(n, std::numeric_limits<double>::quiet_NaN());
  top.stats.pixels = static_cast<long long>(n);
  if (tessellation.points.empty()) {
    top.stats.misses = top.stats.pixels;
    return top;
  }

  double z_min = std::numeric_limits<double>::infinity();
  double z_max = -z_min;
  for (const Eigen::Vector3d& p : tessellation.points) {
    z_min = std::min(z_min, p.z());
    z_max = std::max(z_max, p.z());
  }
  const double z_start = z_max + options.start_margin;
  const float t_far = static_cast<float>(z_start - z_min + options.start_margin);
  const RTCScene rtc_scene = scene.get();

  tbb::combinable<TopViewStats> local_stats;
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.height), [&](const tbb::blocked_range<int>& rows) {
    TopViewStats& stats = local_stats.local();
    for (int row = rows.begin(); row < rows.end(); ++row) {
      CastRow(rtc_scene, tessellation, options, row, z_start, t_far, &top, &stats);
    }
  });
  scene.device().Check();
  local_stats.combine_each([&](const TopViewStats& s) {
    top.stats.hits += s.hits;
    top.stats.misses += s.misses;
    top.stats.back_faces += s.back_faces;
  });
  return top;
}

Raster MakeDsm(const TopView& top, float nodata) {
  Raster dsm;
  dsm.Allocate(top.grid, 1, RasterType::kFloat32, nodata);
  dsm.nodata = nodata;
  for (size_t i = 0; i < top.facet.size(); ++i) {
    if (top.facet[i] >= 0) dsm.data[i] = static_cast<float>(top.z[i]);
  }
  return dsm;
}

Raster InterpolateNodeValues(const TopView& top, const Tessellation& tessellation,
                             const std::vector<double>& values, int channels, RasterType type,
                             float nodata) {
  if (channels <= 0)
    throw std::invalid_argument("InterpolateNodeValues: channels must be positive");
  if (values.size() != tessellation.points.size() * static_cast<size_t>(channels)) {
    throw std::invalid_argument("InterpolateNodeValues: " + std::to_string(values.size()) +
                                " values for " + std::to_string(tessellation.points.size()) +
                                " nodes x " + std::to_string(channels) + " channels");
  }
  const size_t n = top.facet.size();
  if (n != static_cast<size_t>(top.grid.NumPixels())) {
    throw std::invalid_argument("InterpolateNodeValues: the top view does not match its grid");
  }
  Raster raster;
  raster.Allocate(top.grid, channels, type, nodata);
  raster.nodata = nodata;
  const bool integer = type != RasterType::kFloat32;
  const double max_value = type == RasterType::kUInt8 ? 255.0 : 65535.0;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) {
      const int s = top.facet[i];
      if (s < 0) continue;
      if (s >= static_cast<int>(tessellation.triangles.size())) {
        throw std::invalid_argument("InterpolateNodeValues: facet index out of range");
      }
      const Eigen::Vector3i& t = tessellation.triangles[s];
      const double w1 = top.u[i], w2 = top.v[i], w0 = 1.0 - w1 - w2;
      for (int c = 0; c < channels; ++c) {
        double value = w0 * values[static_cast<size_t>(t[0]) * channels + c] +
                       w1 * values[static_cast<size_t>(t[1]) * channels + c] +
                       w2 * values[static_cast<size_t>(t[2]) * channels + c];
        if (!std::isfinite(value)) continue;  // stays nodata
        if (integer) {
          value = std::clamp(std::round(value), 0.0, max_value);
          if (value == nodata) value += value < max_value ? 1.0 : -1.0;
        }
        raster.data[static_cast<size_t>(c) * n + i] = static_cast<float>(value);
      }
    }
  });
  return raster;
}

Raster MakeOrthophoto(const TopView& top, const Tessellation& tessellation,
                      const std::vector<double>& grey_values, int channels, RasterType type,
                      float nodata) {
  return InterpolateNodeValues(top, tessellation, grey_values, channels, type, nodata);
}

Raster MakeSigmaRaster(const TopView& top, const Tessellation& tessellation,
                       const std::vector<double>& node_sigma, float nodata) {
  return InterpolateNodeValues(top, tessellation, node_sigma, 1, RasterType::kFloat32, nodata);
}

}  // namespace facets
