#include "io/vrml_io.h"

#include <charconv>
#include <filesystem>
#include <stdexcept>
#include <string_view>

#include "io/atomic_file.h"

namespace facets {
namespace {

// Fixed-point, independent of the C and C++ locales.
void AppendFixed(std::string* out, double value, int decimals) {
  char buffer[64];
  if (value == 0) value = 0;  // no "-0.000000"
  const auto result =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::fixed, decimals);
  if (result.ec != std::errc()) {
    throw std::invalid_argument("VRML: cannot format the number " + std::to_string(value));
  }
  std::string_view text(buffer, static_cast<size_t>(result.ptr - buffer));
  if (text.find_first_not_of("-0.") == std::string_view::npos) text = "0";
  out->append(text);
}

void AppendInt(std::string* out, long long value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out->append(buffer, result.ptr);
}

// A VRML SFString: double quotes, with '"' and '\' escaped.
std::string Quoted(const std::string& text) {
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') quoted += '\\';
    quoted += c;
  }
  return quoted + "\"";
}

// "a b c" with `decimals` fixed decimals.
void AppendTriple(std::string* out, const Eigen::Vector3d& v, int decimals) {
  for (int c = 0; c < 3; ++c) {
    if (c) *out += ' ';
    AppendFixed(out, v[c], decimals);
  }
}

// The file header, WorldInfo (origin, crs, up axis, units) and the Transform to the
// origin, up to the opening of the Shape's Appearance.
void AppendHeader(std::string* out, const ExportSurface& surface, int decimals) {
  *out += "#VRML V2.0 utf8\n";
  *out += "# Facets surface: local coordinates; global = Transform translation + local.\n";
  *out += "WorldInfo {\n  title \"Facets surface\"\n  info [ ";
  std::string origin = "origin ";
  AppendTriple(&origin, surface.origin, decimals);
  *out += Quoted(origin) + ", " +
          Quoted("crs " + (surface.crs.empty() ? std::string("unknown") : surface.crs)) +
          ", \"up Z\", \"units m\" ]\n}\n";
  *out += "Transform {\n  translation ";
  AppendTriple(out, surface.origin, decimals);
  *out += "\n  children [\n    Shape {\n      appearance Appearance {\n";
}

// Coordinate points (local, m) and the triangles' coordIndex.
void AppendCoordinates(std::string* out, const ExportSurface& surface, int decimals) {
  *out += "        coord Coordinate { point [\n";
  for (const Eigen::Vector3d& v : surface.vertices) {
    *out += "          ";
    AppendTriple(out, v, decimals);
    *out += ",\n";
  }
  *out += "        ] }\n        coordIndex [\n";
  for (const Eigen::Vector3i& t : surface.triangles) {
    *out += "          ";
    for (int k = 0; k < 3; ++k) {
      AppendInt(out, t[k]);
      *out += ' ';
    }
    *out += "-1,\n";
  }
  *out += "        ]\n";
}

void AppendNormals(std::string* out, const std::vector<Eigen::Vector3d>& normals) {
  *out += "        normalPerVertex TRUE\n        normal Normal { vector [\n";
  for (const Eigen::Vector3d& n : normals) {
    *out += "          ";
    AppendTriple(out, n, 6);
    *out += ",\n";
  }
  *out += "        ] }\n";
}

// One texture coordinate per triangle corner (corner 3 t + k of triangle t).
void AppendTextureCoordinates(std::string* out, const TextureAtlas& atlas, size_t num_triangles) {
  // VRML texture coordinates have t up from the bottom row; the atlas uv has v down.
  *out += "        texCoord TextureCoordinate { point [\n";
  for (const Eigen::Vector2f& uv : atlas.uv) {
    *out += "          ";
    AppendFixed(out, uv.x(), 7);
    *out += ' ';
    AppendFixed(out, 1.0 - static_cast<double>(uv.y()), 7);
    *out += ",\n";
  }
  *out += "        ] }\n        texCoordIndex [\n";
  for (size_t t = 0; t < num_triangles; ++t) {
    *out += "          ";
    for (int k = 0; k < 3; ++k) {
      AppendInt(out, static_cast<long long>(3 * t + k));
      *out += ' ';
    }
    *out += "-1,\n";
  }
  *out += "        ]\n";
}

// Per-vertex colours as sRGB 0..1 from the linear 0..255 colours; one channel repeated
// as grey.
void AppendVertexColors(std::string* out, const ExportSurface& surface) {
  const int ch = surface.channels;
  *out += "        colorPerVertex TRUE\n        color Color { color [\n";
  for (size_t v = 0; v < surface.vertices.size(); ++v) {
    *out += "          ";
    for (int c = 0; c < 3; ++c) {
      if (c) *out += ' ';
      const float linear = surface.colors[v * ch + (ch == 3 ? c : 0)];
      AppendFixed(out, LinearToSrgb8(linear) / 255.0, 4);
    }
    *out += ",\n";
  }
  *out += "        ] }\n";
}

}  // namespace

void VrmlOptions::Check() const {
  if (atlas_cell_px < 5) {
    throw std::invalid_argument("VrmlOptions.atlas_cell_px must be >= 5, not " +
                                std::to_string(atlas_cell_px));
  }
  if (max_atlas_px < atlas_cell_px) {
    throw std::invalid_argument("VrmlOptions.max_atlas_px must be >= atlas_cell_px, not " +
                                std::to_string(max_atlas_px));
  }
  if (coordinate_decimals < 1 || coordinate_decimals > 12) {
    throw std::invalid_argument("VrmlOptions.coordinate_decimals must be 1..12, not " +
                                std::to_string(coordinate_decimals));
  }
}

std::string VrmlAtlasPath(const std::string& path) {
  std::filesystem::path p(path);
  return (p.parent_path() / (p.stem().string() + "_atlas.png")).string();
}

std::string VrmlText(const ExportSurface& surface, const VrmlOptions& options,
                     const std::string& texture_url, const std::string& what,
                     TextureAtlas* atlas_out) {
  options.Check();
  surface.Check(what);
  if (surface.triangles.empty())
    throw std::invalid_argument(what + ": the surface has no triangles");
  const bool has_color = !surface.colors.empty();
  const bool textured = has_color && options.color_mode == VrmlColorMode::kTexture;
  const bool vertex_colors = has_color && options.color_mode == VrmlColorMode::kVertexColors;
  const int d = options.coordinate_decimals;

  std::string out;
  out.reserve(64 * surface.vertices.size() + 32 * surface.triangles.size() + 1024);
  AppendHeader(&out, surface, d);
  TextureAtlas atlas;
  if (textured) {
    atlas = BuildTextureAtlas(surface, options.atlas_cell_px, options.max_atlas_px, what);
    out += "        texture ImageTexture { url " + Quoted(texture_url) +
           " repeatS FALSE repeatT FALSE }\n";
  }
  out += "      }\n      geometry IndexedFaceSet {\n";
  out += "        solid FALSE\n        ccw TRUE\n        convex TRUE\n";
  AppendCoordinates(&out, surface, d);
  if (!surface.normals.empty()) AppendNormals(&out, surface.normals);
  if (textured) AppendTextureCoordinates(&out, atlas, surface.triangles.size());
  if (vertex_colors) AppendVertexColors(&out, surface);
  out += "      }\n    }\n  ]\n}\n";
  if (atlas_out != nullptr) *atlas_out = std::move(atlas);
  return out;
}

void WriteVrml(const std::string& path, const ExportSurface& surface, const VrmlOptions& options) {
  const std::string atlas_path = VrmlAtlasPath(path);
  TextureAtlas atlas;
  const std::string text = VrmlText(
      surface, options, std::filesystem::path(atlas_path).filename().string(), path, &atlas);
  if (atlas.width > 0) {
    const std::vector<unsigned char> png = EncodePng(atlas, atlas_path);
    WriteFileAtomically(atlas_path,
                        std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
  }
  WriteFileAtomically(path, text);
}

}  // namespace facets
