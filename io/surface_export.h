// The exchange type between a reconstructed surface and the export writers (glTF
// binary, VRML97): io/gltf_io.h, io/vrml_io.h.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace facets {

// What the export writers need of a reconstructed surface. The object grey value model
// is linear per grey facet, so the tessellated surface (one vertex per grey node, one
// triangle per grey facet) with per-vertex colour represents it exactly.
struct ExportSurface {
  std::vector<Eigen::Vector3d> vertices;   // local object coordinates (global = origin + local)
  std::vector<Eigen::Vector3i> triangles;  // counter-clockwise seen from outside/above
  std::vector<Eigen::Vector3d> normals;    // optional, unit, per vertex
  int channels = 1;                        // 1 (grey) or 3 (RGB)
  std::vector<float> colors;               // optional, vertex-major: colors[v * channels + c], 0..255 linear
  std::vector<float> sigma;                // optional, per vertex, object units (m)
  std::vector<int> views;                  // optional, per vertex
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::string crs;                         // e.g. "EPSG:2180"; "" unknown
  // Throws std::invalid_argument whose message starts with `what` (a file or object
  // name) when an optional vector is neither empty nor one entry per vertex, channels is
  // not 1 or 3, a triangle index is out of range, a normal is not unit length (1e-3), a
  // colour is outside 0..255, a sigma or views value is negative, or any coordinate,
  // normal, colour, sigma or the origin is not finite.
  void Check(const std::string& what) const;
};

// A texture atlas that carries the linear per-triangle colour of an ExportSurface
// exactly (up to 8-bit quantisation), shared by the glTF and VRML writers.
//
// Layout: triangles 2t and 2t+1 share a square cell of cell_px x cell_px texels; cells
// fill rows of a near-square grid. In cell coordinates (texel units, y down) triangle 2t
// has its corners at (1,1), (1+a,1), (1,1+a) and triangle 2t+1 at (c-1,c-1),
// (c-1-a,c-1), (c-1,c-1-a), with c = cell_px and legs a = c - 4. Every texel whose centre
// lies less than one texel (in x and in y) from a triangle holds that triangle's linear
// colour function evaluated at the texel centre (extrapolated outside the triangle).
// Bilinear interpolation reproduces a linear function exactly, so with LINEAR filtering
// and no mipmaps a renderer samples exactly the vertex-colour interpolation; the two
// triangles of a cell and neighbouring cells never share such a texel (no bleeding).
//
// Transfer: colours are linear 0..255; texels are 8-bit sRGB (IEC 61966-2-1 curve,
// LinearToSrgb8), as glTF's baseColorTexture and ordinary PNG viewers expect.
// Extrapolated texels are clamped to 0..255, so within one texel of a triangle edge a
// very steep colour gradient can be clipped.
struct TextureAtlas {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;      // row-major, 3 bytes per texel, sRGB
  std::vector<Eigen::Vector2f> uv;    // per triangle corner uv[3 * t + k]; glTF
                                      // convention: (0,0) top-left, v down, in 0..1
};

// Throws std::invalid_argument (message starts with `what`) when the surface has no
// colours, cell_px < 5, or the atlas would exceed max_px texels on a side.
TextureAtlas BuildTextureAtlas(const ExportSurface& surface, int cell_px, int max_px,
                               const std::string& what);

// The 8-bit sRGB code of a linear value on the 0..255 scale (clamped).
std::uint8_t LinearToSrgb8(float linear_0_255);
// Inverse (for tests and readers): linear 0..255 of an sRGB code.
float Srgb8ToLinear(std::uint8_t srgb);

// The atlas as an 8-bit RGB PNG file in memory (OpenImageIO). Throws
// std::runtime_error starting with `what` on failure.
std::vector<unsigned char> EncodePng(const TextureAtlas& atlas, const std::string& what);

}  // namespace facets
