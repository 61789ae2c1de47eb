#include "io/preview.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "io/image_io.h"

namespace facets {
namespace {

// Unit vector towards azimuth (clockwise from +Y = north) and elevation, in degrees.
Eigen::Vector3d Direction(double azimuth_deg, double elevation_deg) {
  const double a = azimuth_deg * M_PI / 180.0, e = elevation_deg * M_PI / 180.0;
  return {std::sin(a) * std::cos(e), std::cos(a) * std::cos(e), std::sin(e)};
}

// What the z-buffer keeps per sample: the nearest triangle and the barycentric
// weights of corners 1 and 2 there.
struct Visibility {
  int width = 0, height = 0;
  std::vector<int> triangle;  // -1 = background
  std::vector<float> w1, w2;
};

Visibility RasteriseSamples(const ExportSurface& surface, const PreviewOptions& o, const PreviewFrame& frame) {
  const int ss = o.supersampling;
  Visibility vis;
  vis.width = o.panel_width * ss;
  vis.height = o.panel_height * ss;
  const size_t n = static_cast<size_t>(vis.width) * vis.height;
  vis.triangle.assign(n, -1);
  vis.w1.assign(n, 0.0f);
  vis.w2.assign(n, 0.0f);
  std::vector<double> depth(n, -std::numeric_limits<double>::infinity());

  // Camera frame: `toward` points at the viewer, right and up span the picture.
  const Eigen::Vector3d toward = frame.toward;
  const Eigen::Vector3d right = (-toward).cross(frame.vertical).normalized();
  const Eigen::Vector3d up = right.cross(-toward);
  // Picture coordinates relative to the surface's centre (local coordinates can be far
  // from zero; the differences stay exact enough in double).
  Eigen::AlignedBox2d box;
  for (const Eigen::Vector3d& p : surface.vertices) box.extend(Eigen::Vector2d(p.dot(right), p.dot(up)));
  const Eigen::Vector2d size = box.sizes().cwiseMax(1e-9);
  const double margin = static_cast<double>(o.margin_px) * ss;
  const double scale =
      std::min((vis.width - 2.0 * margin) / size.x(), (vis.height - 2.0 * margin) / size.y());
  const Eigen::Vector2d centre = box.center();
  std::vector<Eigen::Vector3d> screen(surface.vertices.size());  // x right, y down, depth
  for (size_t i = 0; i < surface.vertices.size(); ++i) {
    const Eigen::Vector3d& p = surface.vertices[i];
    screen[i] = {0.5 * vis.width + (p.dot(right) - centre.x()) * scale,
                 0.5 * vis.height - (p.dot(up) - centre.y()) * scale, p.dot(toward)};
  }

  for (size_t t = 0; t < surface.triangles.size(); ++t) {
    const Eigen::Vector3d& a = screen[surface.triangles[t][0]];
    const Eigen::Vector3d& b = screen[surface.triangles[t][1]];
    const Eigen::Vector3d& c = screen[surface.triangles[t][2]];
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) continue;  // seen edge-on: covers no sample
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(vis.width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(vis.height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        // Barycentric weights from signed areas; all >= 0 inside, either winding.
        const double w1 = ((c.x() - a.x()) * (py - a.y()) - (c.y() - a.y()) * (px - a.x())) / -area;
        const double w2 = ((b.x() - a.x()) * (py - a.y()) - (b.y() - a.y()) * (px - a.x())) / area;
        const double w0 = 1.0 - w1 - w2;
        if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) continue;
        const double z = w0 * a.z() + w1 * b.z() + w2 * c.z();
        const size_t i = static_cast<size_t>(y) * vis.width + x;
        if (z <= depth[i]) continue;
        depth[i] = z;
        vis.triangle[i] = static_cast<int>(t);
        vis.w1[i] = static_cast<float>(w1);
        vis.w2[i] = static_cast<float>(w2);
      }
    }
  }
  return vis;
}

}  // namespace

PreviewFrame ChoosePreviewFrame(const ExportSurface& surface, const PreviewOptions& o) {
  PreviewFrame frame;
  frame.toward = Direction(o.view_azimuth_deg, o.view_elevation_deg);
  frame.light = Direction(o.light_azimuth_deg, o.light_elevation_deg);
  frame.vertical = Eigen::Vector3d::UnitZ();
  if (!o.facade_frame) return frame;
  // Area-weighted mean normal (the triangles' winding) and the area.
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double area = 0.0;
  for (const Eigen::Vector3i& t : surface.triangles) {
    const Eigen::Vector3d n = 0.5 * (surface.vertices[t[1]] - surface.vertices[t[0]])
                                        .cross(surface.vertices[t[2]] - surface.vertices[t[0]]);
    sum += n;
    area += n.norm();
  }
  if (!(area > 0.0) || sum.norm() < o.facade_min_flatness * area) return frame;  // closed or crumpled
  const Eigen::Vector3d zenith = sum.normalized();
  if (std::abs(zenith.z()) >= std::cos(o.facade_min_tilt_deg * M_PI / 180.0)) return frame;  // faces +-Z
  // North: `up` in the surface's plane; Z, then X when `up` is (nearly) the normal.
  Eigen::Vector3d north = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& candidate : {o.up, Eigen::Vector3d::UnitZ().eval(), Eigen::Vector3d::UnitX().eval()}) {
    if (!(candidate.norm() > 0.0)) continue;
    const Eigen::Vector3d c = candidate.normalized();
    const Eigen::Vector3d in_plane = c - c.dot(zenith) * zenith;
    if (in_plane.norm() > 0.2) {
      north = in_plane.normalized();
      break;
    }
  }
  const Eigen::Vector3d east = north.cross(zenith);
  auto direction = [&](double azimuth_deg, double elevation_deg) {
    const Eigen::Vector3d d = Direction(azimuth_deg, elevation_deg);
    return Eigen::Vector3d(d.x() * east + d.y() * north + d.z() * zenith);
  };
  frame.toward = direction(o.view_azimuth_deg, o.facade_view_elevation_deg);
  frame.light = direction(o.light_azimuth_deg, o.light_elevation_deg);
  frame.vertical = north;
  frame.facade = true;
  return frame;
}

void PreviewOptions::Check() const {
  auto fail = [](const std::string& m) { throw std::invalid_argument("preview options: " + m); };
  if (panel_width < 16 || panel_height < 16 || panel_width > 8192 || panel_height > 8192) {
    fail("panel_width and panel_height must be 16..8192");
  }
  if (!(view_elevation_deg > -90.0 && view_elevation_deg < 90.0)) {
    fail("view_elevation_deg must be inside -90..90 (exclusive: the picture needs a horizon direction)");
  }
  if (!std::isfinite(view_azimuth_deg) || !std::isfinite(light_azimuth_deg) ||
      !std::isfinite(light_elevation_deg)) {
    fail("azimuths and elevations must be finite");
  }
  if (!(ambient >= 0.0 && ambient <= 1.0)) fail("ambient must be 0..1");
  if (!(facade_view_elevation_deg > -90.0 && facade_view_elevation_deg < 90.0)) {
    fail("facade_view_elevation_deg must be inside -90..90 (exclusive)");
  }
  if (!(facade_min_tilt_deg >= 0.0 && facade_min_tilt_deg <= 90.0)) fail("facade_min_tilt_deg must be 0..90");
  if (!(facade_min_flatness >= 0.0 && facade_min_flatness <= 1.0)) fail("facade_min_flatness must be 0..1");
  if (!up.allFinite()) fail("up must be finite");
  if (supersampling < 1 || supersampling > 8) fail("supersampling must be 1..8");
  if (margin_px < 0 || 2 * margin_px >= std::min(panel_width, panel_height)) {
    fail("margin_px must be >= 0 and leave room for the surface");
  }
}

PreviewImage RenderPreview(const ExportSurface& surface, const PreviewOptions& options,
                           const std::string& what) {
  options.Check();
  surface.Check(what);
  if (surface.triangles.empty()) throw std::invalid_argument(what + ": the surface has no triangles");
  const PreviewFrame frame = ChoosePreviewFrame(surface, options);
  const Visibility vis = RasteriseSamples(surface, options, frame);

  const Eigen::Vector3d toward = frame.toward;
  const Eigen::Vector3d light = frame.light;
  const bool coloured = !surface.colors.empty();
  const int ch = surface.channels;
  // Per sample: shaded grey and textured RGB.
  auto shaded = [&](int t) {
    const Eigen::Vector3i& tri = surface.triangles[t];
    Eigen::Vector3d n = (surface.vertices[tri[1]] - surface.vertices[tri[0]])
                            .cross(surface.vertices[tri[2]] - surface.vertices[tri[0]]);
    if (n.squaredNorm() == 0.0) return 255.0 * options.ambient;
    n.normalize();
    if (n.dot(toward) < 0.0) n = -n;  // the side the viewer sees
    // Shown directly as the display value, as a GIS hillshade does: an sRGB-encoded
    // (physically displayed) Lambert term pushes every lit slope towards white and
    // hides the shape.
    return 255.0 * (options.ambient + (1.0 - options.ambient) * std::max(0.0, n.dot(light)));
  };
  auto textured = [&](int t, float w1, float w2, int c) {
    if (!coloured) return 128.0;
    const Eigen::Vector3i& tri = surface.triangles[t];
    const int k = ch == 1 ? 0 : c;
    const double value = (1.0 - w1 - w2) * surface.colors[tri[0] * ch + k] +
                         w1 * surface.colors[tri[1] * ch + k] + w2 * surface.colors[tri[2] * ch + k];
    return std::clamp(value, 0.0, 255.0);
  };

  const int ss = options.supersampling;
  PreviewImage image;
  image.width = 2 * options.panel_width;
  image.height = options.panel_height;
  image.rgb.resize(static_cast<size_t>(image.width) * image.height * 3);
  for (int y = 0; y < options.panel_height; ++y) {
    for (int x = 0; x < options.panel_width; ++x) {
      double left[3] = {0, 0, 0}, right[3] = {0, 0, 0};
      for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
          const size_t i = static_cast<size_t>(y * ss + sy) * vis.width + (x * ss + sx);
          const int t = vis.triangle[i];
          for (int c = 0; c < 3; ++c) {
            if (t < 0) {
              left[c] += options.background[c];
              right[c] += options.background[c];
            } else {
              left[c] += shaded(t);
              right[c] += textured(t, vis.w1[i], vis.w2[i], c);
            }
          }
        }
      }
      const double samples = static_cast<double>(ss) * ss;
      for (int c = 0; c < 3; ++c) {
        const size_t row = static_cast<size_t>(y) * image.width;
        image.rgb[(row + x) * 3 + c] = static_cast<std::uint8_t>(std::lround(left[c] / samples));
        image.rgb[(row + options.panel_width + x) * 3 + c] =
            static_cast<std::uint8_t>(std::lround(right[c] / samples));
      }
    }
  }
  return image;
}

void WritePreview(const std::string& path, const ExportSurface& surface,
                  const PreviewOptions& options) {
  const PreviewImage image = RenderPreview(surface, options, path);
  ImagePlanes planes;
  planes.width = image.width;
  planes.height = image.height;
  planes.channels = 3;
  const size_t plane = static_cast<size_t>(image.width) * image.height;
  planes.data.resize(plane * 3);
  for (size_t i = 0; i < plane; ++i) {
    for (int c = 0; c < 3; ++c) planes.data[c * plane + i] = image.rgb[i * 3 + c];
  }
  WriteImage(path, planes, 8);  // OpenImageIO, a unique temporary + rename
}

}  // namespace facets
