#include "io/vrml_io.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "io/products_dir_for_testing.h"
#include "io/surface_export.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

// A tent roof over a flat square: two planes meeting at a ridge, RGB or grey colours.
ExportSurface TentSurface(int n, int channels) {
  ExportSurface s;
  s.channels = channels;
  s.origin = Eigen::Vector3d(654321.125, 5432109.875, 250.25);
  s.crs = "EPSG:2180";
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = 10.0 * i / (n - 1) - 5.0, y = 10.0 * j / (n - 1) - 5.0;
      s.vertices.emplace_back(x, y, 3.0 - 0.4 * std::abs(y));
      s.normals.push_back(Eigen::Vector3d(0, y > 0 ? 0.4 : (y < 0 ? -0.4 : 0), 1).normalized());
      for (int c = 0; c < channels; ++c) {
        s.colors.push_back(static_cast<float>(128 + 90 * std::cos(0.7 * x + 0.5 * y + 2 * c)));
      }
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      s.triangles.emplace_back(a, b, d);
      s.triangles.emplace_back(a, d, c);
    }
  }
  return s;
}

// The numbers of the first "[ ... ]" list after `key` (commas are separators).
std::vector<double> ListAfter(const std::string& text, const std::string& key) {
  const size_t at = text.find(key);
  if (at == std::string::npos) return {};
  const size_t open = text.find('[', at);
  const size_t close = text.find(']', open);
  std::string body = text.substr(open + 1, close - open - 1);
  std::replace(body.begin(), body.end(), ',', ' ');
  std::istringstream in(body);
  in.imbue(std::locale::classic());
  std::vector<double> values;
  for (double v; in >> v;) values.push_back(v);
  return values;
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(VrmlIo, TexturedFileParsesBackWithCountsAndCoordinates) {
  const ExportSurface surface = TentSurface(21, 1);
  const fs::path path = ProductsDir() / "tent_grey_textured.wrl";
  WriteVrml(path.string(), surface);
  const std::string text = ReadText(path);
  ASSERT_EQ(text.rfind("#VRML V2.0 utf8\n", 0), 0u);
  EXPECT_NE(text.find("solid FALSE"), std::string::npos);
  EXPECT_NE(text.find("ccw TRUE"), std::string::npos);
  EXPECT_NE(text.find("url \"tent_grey_textured_atlas.png\""), std::string::npos);
  EXPECT_EQ(text.find("Material"), std::string::npos);  // unlit
  EXPECT_NE(text.find("crs EPSG:2180"), std::string::npos);

  std::istringstream tr(text.substr(text.find("\n  translation ") + 14));
  tr.imbue(std::locale::classic());
  Eigen::Vector3d origin;
  tr >> origin.x() >> origin.y() >> origin.z();
  EXPECT_LT((origin - surface.origin).norm(), 1e-6);

  const std::vector<double> points = ListAfter(text, "Coordinate {");
  const std::vector<double> index = ListAfter(text, "coordIndex");
  const std::vector<double> normals = ListAfter(text, "Normal {");
  const std::vector<double> tex = ListAfter(text, "TextureCoordinate {");
  const std::vector<double> tex_index = ListAfter(text, "texCoordIndex");
  ASSERT_EQ(points.size(), 3 * surface.vertices.size());
  ASSERT_EQ(index.size(), 4 * surface.triangles.size());
  EXPECT_EQ(normals.size(), 3 * surface.vertices.size());
  EXPECT_EQ(tex.size(), 2 * 3 * surface.triangles.size());
  EXPECT_EQ(tex_index.size(), 4 * surface.triangles.size());
  double max_error = 0;
  for (size_t v = 0; v < surface.vertices.size(); ++v) {
    max_error = std::max(
        max_error,
        (Eigen::Vector3d(points[3 * v], points[3 * v + 1], points[3 * v + 2]) - surface.vertices[v])
            .norm());
  }
  int index_mismatch = 0;
  for (size_t t = 0; t < surface.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) index_mismatch += index[4 * t + k] != surface.triangles[t][k];
    index_mismatch += index[4 * t + 3] != -1;
  }
  std::cout << "wrl: " << points.size() / 3 << " points, " << index.size() / 4
            << " faces, max coordinate error " << max_error << " m\n";
  EXPECT_LT(max_error, 6e-7);  // 6 decimals: half a micrometre
  EXPECT_EQ(index_mismatch, 0);

  // The atlas beside the file, readable, with the size the texture coordinates assume.
  const fs::path atlas_path = VrmlAtlasPath(path.string());
  ASSERT_TRUE(fs::exists(atlas_path));
  EXPECT_FALSE(fs::exists(path.string() + ".tmp"));
  auto in = OIIO::ImageInput::open(atlas_path.string());
  ASSERT_TRUE(in);
  const TextureAtlas atlas = BuildTextureAtlas(surface, 6, 16384, "test");
  EXPECT_EQ(in->spec().width, atlas.width);
  EXPECT_EQ(in->spec().height, atlas.height);
  std::vector<uint8_t> pixels(static_cast<size_t>(atlas.width) * atlas.height * 3);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, pixels.data()));
  EXPECT_EQ(pixels, atlas.rgb);
  // VRML t runs up from the bottom row: t = 1 - v.
  EXPECT_NEAR(tex[1], 1.0 - atlas.uv[0].y(), 1e-7);
}

TEST(VrmlIo, VertexColoursAreDisplayEncoded) {
  const ExportSurface surface = TentSurface(11, 3);
  VrmlOptions options;
  options.color_mode = VrmlColorMode::kVertexColors;
  const fs::path path = ProductsDir() / "tent_rgb_vertex_colors.wrl";
  WriteVrml(path.string(), surface, options);
  EXPECT_FALSE(fs::exists(VrmlAtlasPath(path.string())));
  const std::string text = ReadText(path);
  EXPECT_EQ(text.find("ImageTexture"), std::string::npos);
  const std::vector<double> colors = ListAfter(text, "Color {");
  ASSERT_EQ(colors.size(), 3 * surface.vertices.size());
  double max_error = 0;
  for (size_t i = 0; i < colors.size(); ++i) {
    max_error = std::max(max_error, std::abs(colors[i] - LinearToSrgb8(surface.colors[i]) / 255.0));
  }
  std::cout << "wrl Color: " << colors.size() / 3 << " colours, max error " << max_error << "\n";
  EXPECT_LT(max_error, 5.1e-5);  // 4 decimals
}

TEST(VrmlIo, GeometryOnlyAndBadInput) {
  ExportSurface surface = TentSurface(5, 1);
  surface.colors.clear();
  surface.normals.clear();
  const fs::path path = ProductsDir() / "tent_geometry_only.wrl";
  WriteVrml(path.string(), surface);
  const std::string text = ReadText(path);
  EXPECT_EQ(text.find("Normal"), std::string::npos);
  EXPECT_EQ(ListAfter(text, "coordIndex").size(), 4 * surface.triangles.size());

  const std::string bad = (fs::path(testing::TempDir()) / "bad.wrl").string();
  surface.triangles[0][0] = -3;
  try {
    WriteVrml(bad, surface);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    std::cout << "rejected: " << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("triangle 0 has vertex index -3"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(bad));
  VrmlOptions options;
  options.coordinate_decimals = 0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  EXPECT_THROW(
      WriteVrml((fs::path(testing::TempDir()) / "no_dir" / "x.wrl").string(), TentSurface(3, 1)),
      std::runtime_error);
}

}  // namespace
}  // namespace facets
