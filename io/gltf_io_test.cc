#include "io/gltf_io.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include "io/products_dir_for_testing.h"
#include "io/surface_export.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

// A wavy grid surface nx x ny with analytic unit normals, smooth colours in 20..235,
// sigma and views. Vertex i's views value is i % 7 + 2; its sigma 0.01 + 1e-6 i.
ExportSurface GridSurface(int nx, int ny, int channels, double spacing = 0.5) {
  ExportSurface s;
  s.channels = channels;
  s.origin = Eigen::Vector3d(500123.25, 5800456.75, 120.5);
  s.crs = "EPSG:25833";
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double x = i * spacing - 10.0, y = j * spacing - 7.0;
      const double z = 2.0 * std::sin(x / 7.0) + std::cos(y / 5.0);
      const Eigen::Vector3d n(-2.0 / 7.0 * std::cos(x / 7.0), std::sin(y / 5.0) / 5.0, 1.0);
      s.vertices.emplace_back(x, y, z);
      s.normals.push_back(n.normalized());
      for (int c = 0; c < channels; ++c) {
        s.colors.push_back(static_cast<float>(127.5 + 100.0 * std::sin(0.3 * x + 0.2 * y + c)));
      }
      const int v = static_cast<int>(s.vertices.size()) - 1;
      s.sigma.push_back(0.01f + 1e-6f * static_cast<float>(v));
      s.views.push_back(v % 7 + 2);
    }
  }
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      s.triangles.emplace_back(a, b, d);  // counter-clockwise seen from above
      s.triangles.emplace_back(a, d, c);
    }
  }
  return s;
}

tinygltf::Model Load(const std::string& bytes) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  const bool ok = loader.LoadBinaryFromMemory(&model, &err, &warn,
                                              reinterpret_cast<const unsigned char*>(bytes.data()),
                                              static_cast<unsigned int>(bytes.size()));
  EXPECT_TRUE(ok) << err;
  EXPECT_EQ(warn, "");
  return model;
}

// Accessor values as doubles (float, unsigned short or unsigned int components).
std::vector<double> Values(const tinygltf::Model& model, int accessor_index) {
  const tinygltf::Accessor& a = model.accessors.at(accessor_index);
  const tinygltf::BufferView& view = model.bufferViews.at(a.bufferView);
  const unsigned char* p =
      model.buffers.at(view.buffer).data.data() + view.byteOffset + a.byteOffset;
  const size_t n = a.count * tinygltf::GetNumComponentsInType(a.type);
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i) {
    switch (a.componentType) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float f;
        std::memcpy(&f, p + 4 * i, 4);
        out[i] = f;
        break;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t u;
        std::memcpy(&u, p + 2 * i, 2);
        out[i] = u;
        break;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t u;
        std::memcpy(&u, p + 4 * i, 4);
        out[i] = u;
        break;
      }
      default:
        ADD_FAILURE() << "unexpected component type " << a.componentType;
    }
  }
  return out;
}

const tinygltf::Node& MeshNode(const tinygltf::Model& model) {
  for (const tinygltf::Node& node : model.nodes) {
    if (node.mesh >= 0) return node;
  }
  throw std::runtime_error("no mesh node");
}

// Linear 0..255 value of channel c at uv, bilinear in linear space (what a GPU does
// with an sRGB texture and LINEAR filtering).
double SampleAtlas(const tinygltf::Image& image, double u, double v, int c) {
  const double x = u * image.width - 0.5, y = v * image.height - 0.5;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  auto texel = [&](int xi, int yi) {
    xi = std::clamp(xi, 0, image.width - 1);
    yi = std::clamp(yi, 0, image.height - 1);
    return static_cast<double>(Srgb8ToLinear(
        image.image[(static_cast<size_t>(yi) * image.width + xi) * image.component + c]));
  };
  return (1 - fy) * ((1 - fx) * texel(x0, y0) + fx * texel(x0 + 1, y0)) +
         fy * ((1 - fx) * texel(x0, y0 + 1) + fx * texel(x0 + 1, y0 + 1));
}

TEST(GltfIo, TexturedRoundTripKeepsGeometryAttributesAndColours) {
  const ExportSurface surface = GridSurface(40, 30, 1);
  const std::string bytes = GlbBytes(surface);
  const tinygltf::Model model = Load(bytes);

  // Georeference: extras and the mesh node's translation (double).
  ASSERT_TRUE(model.asset.extras.Has("facets"));
  const tinygltf::Value& geo = model.asset.extras.Get("facets");
  EXPECT_EQ(geo.Get("crs").Get<std::string>(), "EPSG:25833");
  EXPECT_EQ(geo.Get("origin").Get(0).GetNumberAsDouble(), surface.origin.x());
  EXPECT_EQ(geo.Get("origin").Get(1).GetNumberAsDouble(), surface.origin.y());
  ASSERT_EQ(model.scenes.size(), 1u);
  EXPECT_TRUE(model.scenes[0].extras.Has("facets"));
  const tinygltf::Node& node = MeshNode(model);
  ASSERT_EQ(node.translation.size(), 3u);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(node.translation[c], surface.origin[c]);
  EXPECT_EQ(model.extensionsUsed, std::vector<std::string>{"KHR_materials_unlit"});

  ASSERT_EQ(model.meshes.size(), 1u);
  ASSERT_EQ(model.images.size(), 1u);
  const tinygltf::Image& image = model.images[0];
  ASSERT_GT(image.width, 0);
  ASSERT_GE(image.component, 3);

  size_t triangles = 0;
  double max_position_error = 0, max_normal_error = 0, max_colour_error = 0;
  double max_sigma_error = 0;
  int views_mismatch = 0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const tinygltf::Primitive& p : model.meshes[0].primitives) {
    const std::vector<double> pos = Values(model, p.attributes.at("POSITION"));
    const std::vector<double> nor = Values(model, p.attributes.at("NORMAL"));
    const std::vector<double> uv = Values(model, p.attributes.at("TEXCOORD_0"));
    const std::vector<double> sig = Values(model, p.attributes.at("_SIGMA"));
    const std::vector<double> vie = Values(model, p.attributes.at("_VIEWS"));
    const std::vector<double> idx = Values(model, p.indices);
    EXPECT_EQ(model.accessors[p.indices].componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
    // Textured: three vertices per triangle, in triangle order.
    for (size_t k = 0; k < idx.size(); ++k) {
      const size_t t = triangles + k / 3;
      const int v = surface.triangles[t][static_cast<int>(k % 3)];
      const size_t i = static_cast<size_t>(idx[k]);
      const Eigen::Vector3d global =
          surface.origin + Eigen::Vector3d(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
      max_position_error =
          std::max(max_position_error, (global - (surface.origin + surface.vertices[v])).norm());
      max_normal_error = std::max(
          max_normal_error,
          (Eigen::Vector3d(nor[3 * i], nor[3 * i + 1], nor[3 * i + 2]) - surface.normals[v])
              .norm());
      max_sigma_error = std::max(max_sigma_error, std::abs(sig[i] - surface.sigma[v]));
      if (vie[i] != surface.views[v]) ++views_mismatch;
    }
    // Colour at random points of every triangle vs the linear vertex-colour model.
    for (size_t k = 0; k + 2 < idx.size(); k += 3) {
      const size_t t = triangles + k / 3;
      double b1 = unit(rng), b2 = unit(rng);
      if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
      const double b0 = 1 - b1 - b2;
      const size_t i0 = static_cast<size_t>(idx[k]), i1 = static_cast<size_t>(idx[k + 1]),
                   i2 = static_cast<size_t>(idx[k + 2]);
      const double u = b0 * uv[2 * i0] + b1 * uv[2 * i1] + b2 * uv[2 * i2];
      const double v = b0 * uv[2 * i0 + 1] + b1 * uv[2 * i1 + 1] + b2 * uv[2 * i2 + 1];
      const Eigen::Vector3i& tri = surface.triangles[t];
      const double expected =
          b0 * surface.colors[tri[0]] + b1 * surface.colors[tri[1]] + b2 * surface.colors[tri[2]];
      for (int c = 0; c < 3; ++c) {
        max_colour_error =
            std::max(max_colour_error, std::abs(SampleAtlas(image, u, v, c) - expected));
      }
    }
    triangles += idx.size() / 3;
  }
  std::cout << "textured round trip: " << triangles << " triangles, atlas " << image.width << " x "
            << image.height << ", max position error " << max_position_error
            << " m, max normal error " << max_normal_error << ", max sigma error "
            << max_sigma_error << ", max colour error " << max_colour_error
            << " grey values (linear 0..255)\n";
  EXPECT_EQ(triangles, surface.triangles.size());
  // float32 of local coordinates within +-20 m: half an ulp is < 1e-6 m.
  EXPECT_LT(max_position_error, 2e-6);
  EXPECT_LT(max_normal_error, 1e-6);
  EXPECT_LT(max_sigma_error, 1e-8);
  EXPECT_EQ(views_mismatch, 0);
  // 8-bit sRGB quantisation: at most half a code step, 1.2 linear units at the top.
  EXPECT_LT(max_colour_error, 1.3);

  WriteGlb((ProductsDir() / "grid_grey_textured.glb").string(), surface);
}

TEST(GltfIo, VertexColoursAreLinearAndExact) {
  ExportSurface surface = GridSurface(25, 20, 3);
  for (size_t i = 0; i < surface.views.size(); ++i) surface.views[i] = static_cast<int>(i);
  GlbOptions options;
  options.color_mode = GlbColorMode::kVertexColors;
  const tinygltf::Model model = Load(GlbBytes(surface, options));
  EXPECT_TRUE(model.images.empty());
  ASSERT_EQ(model.meshes[0].primitives.size(), 1u);
  const tinygltf::Primitive& p = model.meshes[0].primitives[0];
  const std::vector<double> col = Values(model, p.attributes.at("COLOR_0"));
  const std::vector<double> vie = Values(model, p.attributes.at("_VIEWS"));
  ASSERT_EQ(col.size(), 3 * surface.vertices.size());  // shared vertices
  // Primitive vertices come in order of first use; _VIEWS (= vertex id here) maps them.
  double max_error = 0;
  std::set<int> seen;
  for (size_t i = 0; i < surface.vertices.size(); ++i) {
    const int v = static_cast<int>(vie[i]);
    seen.insert(v);
    for (int c = 0; c < 3; ++c) {
      max_error = std::max(max_error, std::abs(col[3 * i + c] * 255.0 - surface.colors[3 * v + c]));
    }
  }
  EXPECT_EQ(seen.size(), surface.vertices.size());
  std::cout << "COLOR_0: " << surface.vertices.size() << " vertices, max error " << max_error
            << " (linear 0..255)\n";
  EXPECT_LT(max_error, 1e-4);
  WriteGlb((ProductsDir() / "grid_rgb_vertex_colors.glb").string(), surface, options);
}

// Rebuilds the triangles of every primitive as surface vertex ids (POSITION matched
// through _VIEWS, which the test sets to the vertex id).
std::multiset<std::array<int, 3>> Triangles(const tinygltf::Model& model) {
  std::multiset<std::array<int, 3>> out;
  for (const tinygltf::Primitive& p : model.meshes.at(0).primitives) {
    const std::vector<double> id = Values(model, p.attributes.at("_VIEWS"));
    const std::vector<double> idx = Values(model, p.indices);
    for (size_t k = 0; k + 2 < idx.size(); k += 3) {
      out.insert({static_cast<int>(id[static_cast<size_t>(idx[k])]),
                  static_cast<int>(id[static_cast<size_t>(idx[k + 1])]),
                  static_cast<int>(id[static_cast<size_t>(idx[k + 2])])});
    }
  }
  return out;
}

TEST(GltfIo, LargeMeshSplitsInto16BitPrimitivesOrUses32BitIndices) {
  ExportSurface surface = GridSurface(300, 240, 1, 0.1);  // 72000 vertices
  for (size_t i = 0; i < surface.views.size(); ++i) surface.views[i] = static_cast<int>(i);
  std::multiset<std::array<int, 3>> expected;
  for (const Eigen::Vector3i& t : surface.triangles) expected.insert({t[0], t[1], t[2]});

  GlbOptions shared;
  shared.color_mode = GlbColorMode::kVertexColors;
  const tinygltf::Model split = Load(GlbBytes(surface, shared));
  size_t vertices = 0, max_vertices = 0;
  double max_index = 0;
  for (const tinygltf::Primitive& p : split.meshes[0].primitives) {
    const size_t n = split.accessors[p.attributes.at("POSITION")].count;
    vertices += n;
    max_vertices = std::max(max_vertices, n);
    EXPECT_EQ(split.accessors[p.indices].componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
    for (double i : Values(split, p.indices)) max_index = std::max(max_index, i);
  }
  std::cout << "split: " << surface.vertices.size() << " vertices -> "
            << split.meshes[0].primitives.size() << " primitives, " << vertices
            << " vertices in all (largest " << max_vertices << "), max index " << max_index << "\n";
  EXPECT_EQ(split.meshes[0].primitives.size(), 2u);
  EXPECT_LE(max_vertices, 65535u);
  EXPECT_LT(max_index, 65535);
  EXPECT_EQ(Triangles(split), expected);

  GlbOptions wide = shared;
  wide.max_primitive_vertices = 0;
  const tinygltf::Model one = Load(GlbBytes(surface, wide));
  ASSERT_EQ(one.meshes[0].primitives.size(), 1u);
  const tinygltf::Primitive& p = one.meshes[0].primitives[0];
  EXPECT_EQ(one.accessors[p.indices].componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
  EXPECT_EQ(one.accessors[p.attributes.at("POSITION")].count, surface.vertices.size());
  EXPECT_EQ(Triangles(one), expected);

  // Textured: 3 vertices per triangle, 21845 triangles per primitive at most.
  const tinygltf::Model textured = Load(GlbBytes(surface));
  std::cout << "textured split: " << surface.triangles.size() << " triangles -> "
            << textured.meshes[0].primitives.size() << " primitives, atlas "
            << textured.images[0].width << " x " << textured.images[0].height << "\n";
  EXPECT_EQ(textured.meshes[0].primitives.size(), (surface.triangles.size() + 21844) / 21845);
  EXPECT_EQ(Triangles(textured), expected);

  const fs::path dir = ProductsDir();
  WriteGlb((dir / "large_split_vertex_colors.glb").string(), surface, shared);
  WriteGlb((dir / "large_uint32_vertex_colors.glb").string(), surface, wide);
  WriteGlb((dir / "large_split_textured.glb").string(), surface);
}

// Issue 8 round trip with UTM-sized coordinates: origin (500000, 5400000, 300). The
// .glb keeps float32 positions relative to the origin and the origin as the double
// translation of node "facets_origin" (and in the extras); reading both back and
// adding them must give the global positions to 1 mm (float32 of local coordinates
// within +-20 m: a few micrometres). Vertex colours: one glTF vertex per surface vertex.
TEST(GltfIo, UtmOriginRoundTripToAMillimetre) {
  ExportSurface surface = GridSurface(60, 50, 1);
  const Eigen::Vector3d origin(500000.0, 5400000.0, 300.0);
  std::vector<Eigen::Vector3d> global;
  for (Eigen::Vector3d& v : surface.vertices) {
    global.push_back(origin + v + Eigen::Vector3d(0.0001234, 0.0005678, 0.0));
    v = global.back() - origin;
  }
  surface.origin = origin;
  surface.crs = "EPSG:25832";
  for (size_t i = 0; i < surface.views.size(); ++i) surface.views[i] = static_cast<int>(i);
  GlbOptions options;
  options.color_mode = GlbColorMode::kVertexColors;
  const fs::path path = ProductsDir() / "grid_utm_vertex_colors.glb";
  WriteGlb(path.string(), surface, options);
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const tinygltf::Model model = Load(bytes);

  const tinygltf::Node& node = MeshNode(model);
  EXPECT_EQ(node.name, "facets_origin");
  ASSERT_EQ(node.translation.size(), 3u);
  const Eigen::Vector3d file_origin(node.translation[0], node.translation[1], node.translation[2]);
  EXPECT_EQ(file_origin, origin);
  const tinygltf::Value& geo = model.asset.extras.Get("facets");
  EXPECT_EQ(geo.Get("crs").Get<std::string>(), "EPSG:25832");
  for (int c = 0; c < 3; ++c) EXPECT_EQ(geo.Get("origin").Get(c).GetNumberAsDouble(), origin[c]);

  size_t vertices = 0;
  double max_error = 0;
  for (const tinygltf::Primitive& p : model.meshes.at(0).primitives) {
    const std::vector<double> pos = Values(model, p.attributes.at("POSITION"));
    const std::vector<double> id = Values(model, p.attributes.at("_VIEWS"));
    vertices += id.size();
    for (size_t i = 0; i < id.size(); ++i) {
      const Eigen::Vector3d back = file_origin + Eigen::Vector3d(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
      max_error = std::max(max_error, (back - global[static_cast<size_t>(id[i])]).norm());
    }
  }
  std::cout << "UTM glb round trip: " << vertices << " vertices (" << surface.vertices.size()
            << " written), origin " << file_origin.transpose() << ", max global position error "
            << max_error << " m\n";
  EXPECT_EQ(vertices, surface.vertices.size());
  EXPECT_LT(max_error, 1e-3);
  EXPECT_LT(max_error, 1e-5);  // what float32 of local coordinates gives
}

TEST(GltfIo, GeometryOnlyAndZUpOptions) {
  ExportSurface surface = GridSurface(10, 8, 1);
  surface.colors.clear();
  surface.sigma.clear();
  surface.views.clear();
  surface.crs.clear();
  GlbOptions options;
  options.y_up = false;
  const tinygltf::Model model = Load(GlbBytes(surface, options));
  ASSERT_EQ(model.nodes.size(), 1u);
  EXPECT_TRUE(model.extensionsUsed.empty());
  EXPECT_EQ(model.meshes[0].primitives[0].attributes.count("_SIGMA"), 0u);
  EXPECT_EQ(model.meshes[0].primitives[0].attributes.count("TEXCOORD_0"), 0u);
  WriteGlb((ProductsDir() / "grid_geometry_only.glb").string(), surface, options);
}

TEST(GltfIo, RejectsBadSurfacesAndOptionsNamingTheFile) {
  const ExportSurface good = GridSurface(4, 3, 1);
  const std::string path = (fs::path(testing::TempDir()) / "bad.glb").string();
  auto expect_throw = [&](const ExportSurface& s, const std::string& fragment) {
    try {
      WriteGlb(path, s);
      ADD_FAILURE() << "no exception for " << fragment;
    } catch (const std::invalid_argument& e) {
      const std::string message = e.what();
      std::cout << "rejected: " << message << "\n";
      EXPECT_NE(message.find(path), std::string::npos) << message;
      EXPECT_NE(message.find(fragment), std::string::npos) << message;
    }
    EXPECT_FALSE(fs::exists(path));
    EXPECT_FALSE(fs::exists(path + ".tmp"));
  };
  ExportSurface s = good;
  s.triangles[2][1] = 12;
  expect_throw(s, "triangle 2 has vertex index 12");
  s = good;
  s.vertices[1].y() = std::nan("");
  expect_throw(s, "vertex 1 is not finite");
  s = good;
  s.colors.pop_back();
  expect_throw(s, "colour values");
  s = good;
  s.channels = 2;
  expect_throw(s, "channels");
  s = good;
  s.normals[3] *= 2.0;
  expect_throw(s, "normal 3 is not unit");
  s = good;
  s.colors[5] = 300;
  expect_throw(s, "colour value 5");
  s = good;
  s.sigma.resize(2);
  expect_throw(s, "sigma");
  s = good;
  s.views[0] = -1;
  expect_throw(s, "views 0 is negative");
  s = good;
  s.origin.z() = INFINITY;
  expect_throw(s, "origin");
  s = good;
  s.triangles.clear();
  expect_throw(s, "no triangles");

  GlbOptions options;
  options.max_primitive_vertices = 70000;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = GlbOptions();
  options.atlas_cell_px = 4;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = GlbOptions();
  options.max_atlas_px = 64;  // 12 triangles: 3 x 2 cells of 6 px = 18 x 12 px
  EXPECT_NO_THROW(GlbBytes(good, options));
  options.max_atlas_px = 10;
  EXPECT_THROW(GlbBytes(good, options), std::invalid_argument);
}

TEST(GltfIo, WriterLeavesNoTemporaryAndUnwritablePathThrows) {
  const ExportSurface surface = GridSurface(5, 5, 1);
  const fs::path dir = fs::path(testing::TempDir()) / "facets_glb_atomic";
  fs::create_directories(dir);
  const std::string path = (dir / "a.glb").string();
  WriteGlb(path, surface);
  EXPECT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  std::ifstream in(path, std::ios::binary);
  char magic[4];
  in.read(magic, 4);
  EXPECT_EQ(std::string(magic, 4), "glTF");
  EXPECT_THROW(WriteGlb((dir / "missing_dir" / "b.glb").string(), surface), std::runtime_error);
}

TEST(SurfaceExport, SrgbTransferRoundTripsEveryCode) {
  int worst = 0;
  for (int code = 0; code < 256; ++code) {
    worst =
        std::max(worst, std::abs(LinearToSrgb8(Srgb8ToLinear(static_cast<uint8_t>(code))) - code));
  }
  EXPECT_EQ(worst, 0);
  EXPECT_EQ(LinearToSrgb8(0), 0);
  EXPECT_EQ(LinearToSrgb8(255), 255);
  EXPECT_EQ(LinearToSrgb8(-5), 0);
  EXPECT_EQ(LinearToSrgb8(1000), 255);
  // Mid-grey in linear light (18 %) is about code 118 in sRGB.
  EXPECT_NEAR(LinearToSrgb8(0.18f * 255), 118, 1);
}

}  // namespace
}  // namespace facets
