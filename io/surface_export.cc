#include "io/surface_export.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace facets {
namespace {

std::string At(const char* what, size_t index) {
  return std::string(what) + " " + std::to_string(index);
}

}  // namespace

void ExportSurface::Check(const std::string& what) const {
  auto fail = [&](const std::string& message) {
    throw std::invalid_argument(what + ": " + message);
  };
  const size_t n = vertices.size();
  if (channels != 1 && channels != 3) {
    fail("channels must be 1 or 3, not " + std::to_string(channels));
  }
  if (!origin.allFinite()) fail("origin is not finite");
  for (size_t i = 0; i < n; ++i) {
    if (!vertices[i].allFinite()) fail(At("vertex", i) + " is not finite");
  }
  for (size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int v = triangles[t][k];
      if (v < 0 || static_cast<size_t>(v) >= n) {
        fail(At("triangle", t) + " has vertex index " + std::to_string(v) + " outside 0.." +
             std::to_string(static_cast<long long>(n) - 1));
      }
    }
  }
  if (!normals.empty()) {
    if (normals.size() != n) {
      fail(std::to_string(normals.size()) + " normals for " + std::to_string(n) + " vertices");
    }
    for (size_t i = 0; i < n; ++i) {
      const double len = normals[i].norm();
      if (!std::isfinite(len) || std::abs(len - 1.0) > 1e-3) {
        fail(At("normal", i) + " is not unit length (" + std::to_string(len) + ")");
      }
    }
  }
  if (!colors.empty()) {
    if (colors.size() != n * static_cast<size_t>(channels)) {
      fail(std::to_string(colors.size()) + " colour values for " + std::to_string(n) +
           " vertices x " + std::to_string(channels) + " channels");
    }
    for (size_t i = 0; i < colors.size(); ++i) {
      if (!(colors[i] >= 0.0f && colors[i] <= 255.0f)) {
        fail(At("colour value", i) + " is " + std::to_string(colors[i]) + ", not in 0..255");
      }
    }
  }
  if (!sigma.empty()) {
    if (sigma.size() != n) {
      fail(std::to_string(sigma.size()) + " sigma values for " + std::to_string(n) + " vertices");
    }
    for (size_t i = 0; i < n; ++i) {
      if (!(sigma[i] >= 0.0f) || !std::isfinite(sigma[i])) {
        fail(At("sigma", i) + " is " + std::to_string(sigma[i]) + ", not finite and >= 0");
      }
    }
  }
  if (!views.empty()) {
    if (views.size() != n) {
      fail(std::to_string(views.size()) + " views values for " + std::to_string(n) + " vertices");
    }
    for (size_t i = 0; i < n; ++i) {
      if (views[i] < 0) fail(At("views", i) + " is negative (" + std::to_string(views[i]) + ")");
    }
  }
}

std::uint8_t LinearToSrgb8(float linear_0_255) {
  const double l = std::clamp(static_cast<double>(linear_0_255) / 255.0, 0.0, 1.0);
  const double s = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
  return static_cast<std::uint8_t>(std::lround(std::clamp(s, 0.0, 1.0) * 255.0));
}

float Srgb8ToLinear(std::uint8_t srgb) {
  const double s = srgb / 255.0;
  const double l = s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
  return static_cast<float>(l * 255.0);
}

TextureAtlas BuildTextureAtlas(const ExportSurface& surface, int cell_px, int max_px,
                               const std::string& what) {
  if (surface.colors.empty()) throw std::invalid_argument(what + ": no colours for a texture");
  if (cell_px < 5) {
    throw std::invalid_argument(what + ": atlas cell of " + std::to_string(cell_px) +
                                " px is below the minimum of 5");
  }
  const long long tris = static_cast<long long>(surface.triangles.size());
  const long long pairs = std::max(1LL, (tris + 1) / 2);
  const long long cols = static_cast<long long>(std::ceil(std::sqrt(static_cast<double>(pairs))));
  const long long rows = (pairs + cols - 1) / cols;
  if (cols * cell_px > max_px || rows * cell_px > max_px) {
    throw std::invalid_argument(what + ": a texture atlas of " + std::to_string(tris) +
                                " triangles needs " + std::to_string(cols * cell_px) + " x " +
                                std::to_string(rows * cell_px) + " px, more than the limit of " +
                                std::to_string(max_px) +
                                " px (use vertex colours or a smaller atlas cell)");
  }
  TextureAtlas atlas;
  atlas.width = static_cast<int>(cols * cell_px);
  atlas.height = static_cast<int>(rows * cell_px);
  atlas.rgb.assign(static_cast<size_t>(atlas.width) * atlas.height * 3, 0);
  atlas.uv.resize(static_cast<size_t>(tris) * 3);

  const int c = cell_px;
  const double a = c - 4;
  // Corners in cell texel coordinates: triangle 0 (lower-left), triangle 1 (upper-right).
  const double corner[2][3][2] = {{{1, 1}, {1 + a, 1}, {1, 1 + a}},
                                  {{c - 1.0, c - 1.0}, {c - 1 - a, c - 1.0}, {c - 1.0, c - 1 - a}}};
  const int ch = surface.channels;
  for (long long t = 0; t < tris; ++t) {
    const long long pair = t / 2;
    const int half = static_cast<int>(t % 2);
    const int x0 = static_cast<int>((pair % cols) * c);
    const int y0 = static_cast<int>((pair / cols) * c);
    const Eigen::Vector3i& tri = surface.triangles[t];
    for (int k = 0; k < 3; ++k) {
      atlas.uv[3 * t + k] =
          Eigen::Vector2f(static_cast<float>((x0 + corner[half][k][0]) / atlas.width),
                          static_cast<float>((y0 + corner[half][k][1]) / atlas.height));
    }
    float col[3][3];  // [corner][rgb], linear
    for (int k = 0; k < 3; ++k) {
      for (int b = 0; b < 3; ++b) {
        col[k][b] = surface.colors[static_cast<size_t>(tri[k]) * ch + (ch == 3 ? b : 0)];
      }
    }
    for (int j = 0; j < c; ++j) {
      for (int i = 0; i < c; ++i) {
        // Texel centres with i + j + 1 < c are within one texel of triangle 0 only,
        // those with i + j + 1 > c of triangle 1 only; the diagonal (== c) is used by
        // neither and goes to triangle 0.
        const int owner = (i + j + 1 <= c) ? 0 : 1;
        if (owner != half) continue;
        const double x = i + 0.5;
        const double y = j + 0.5;
        const double w1 = half == 0 ? (x - 1) / a : (c - 1 - x) / a;
        const double w2 = half == 0 ? (y - 1) / a : (c - 1 - y) / a;
        const double w0 = 1 - w1 - w2;
        std::uint8_t* texel =
            &atlas.rgb[(static_cast<size_t>(y0 + j) * atlas.width + (x0 + i)) * 3];
        for (int b = 0; b < 3; ++b) {
          texel[b] =
              LinearToSrgb8(static_cast<float>(w0 * col[0][b] + w1 * col[1][b] + w2 * col[2][b]));
        }
      }
    }
  }
  return atlas;
}

std::vector<unsigned char> EncodePng(const TextureAtlas& atlas, const std::string& what) {
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  const std::string name = "atlas.png";
  auto out = OIIO::ImageOutput::create(name);
  if (!out) throw std::runtime_error(what + ": no PNG writer: " + OIIO::geterror());
  if (!out->supports("ioproxy")) {
    throw std::runtime_error(what + ": the PNG writer cannot write to memory");
  }
  OIIO::ImageSpec spec(atlas.width, atlas.height, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", "sRGB");
  out->set_ioproxy(&proxy);
  if (!out->open(name, spec) || !out->write_image(OIIO::TypeDesc::UINT8, atlas.rgb.data()) ||
      !out->close()) {
    throw std::runtime_error(what + ": cannot encode the texture atlas as PNG: " + out->geterror());
  }
  return bytes;
}

}  // namespace facets
