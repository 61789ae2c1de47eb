// glTF and VRML products of every bundled scene's truth mesh (issue 8), written to
// FACETS_PRODUCTS_DIR (default: the test temp folder) for scripts/validate-products.sh,
// which runs the Khronos glTF validator and tovrmlx3d on them.
//
// Colours are the scene's procedural albedo at the vertices (0..255 linear), sigma and
// views are synthetic (smooth functions of position), so every attribute the writers
// know is exercised on real scene geometry: walls, roofs, curved objects, shapes that
// intersect each other.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "io/gltf_io.h"
#include "io/vrml_io.h"
#include "io/products_dir_for_testing.h"
#include "scenes/albedo.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

ExportSurface SurfaceOfScene(const Scene& scene) {
  const TruthMesh mesh = BuildTruthMesh(scene);
  const ProceduralAlbedo albedo(scene.albedo);
  ExportSurface s;
  s.vertices = mesh.vertices;
  s.triangles = mesh.faces;
  s.normals = mesh.normals;
  for (Eigen::Vector3d& n : s.normals) n.normalize();
  s.channels = 1;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    s.colors.push_back(static_cast<float>(255.0 * std::clamp(albedo(v), 0.0, 1.0)));
    s.sigma.push_back(
        static_cast<float>(0.02 + 0.01 * std::sin(0.1 * v.x()) * std::cos(0.1 * v.y())));
    s.views.push_back(2 + static_cast<int>(std::abs(v.x() + v.y())) % 5);
  }
  // Scene coordinates are local; give the products a plausible projected origin so the
  // georeference fields are exercised.
  s.origin = Eigen::Vector3d(500000.0, 5800000.0, 0.0);
  s.crs = "EPSG:25832";
  return s;
}

TEST(ExportProducts, EveryBundledSceneToGlbAndWrl) {
  const fs::path data = fs::path(FACETS_SOURCE_DIR) / "scenes" / "data";
  const fs::path out = ProductsDir();
  int scenes = 0;
  for (const auto& entry : fs::directory_iterator(data)) {
    if (entry.path().extension() != ".json") continue;
    const std::string name = entry.path().stem().string();
    const ExportSurface surface = SurfaceOfScene(LoadScene(entry.path().string()));
    ASSERT_FALSE(surface.triangles.empty()) << name;
    const fs::path glb = out / ("scene_" + name + ".glb");
    const fs::path wrl = out / ("scene_" + name + ".wrl");
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    WriteGlb(glb.string(), surface);
    const auto t1 = Clock::now();
    WriteVrml(wrl.string(), surface);
    const auto t2 = Clock::now();
    GlbOptions vertex_colors;
    vertex_colors.color_mode = GlbColorMode::kVertexColors;
    WriteGlb((out / ("scene_" + name + "_vertex_colors.glb")).string(), surface, vertex_colors);
    EXPECT_GT(fs::file_size(glb), 1000u) << name;
    EXPECT_TRUE(fs::exists(VrmlAtlasPath(wrl.string()))) << name;
    std::cout << name << ": " << surface.vertices.size() << " vertices, "
              << surface.triangles.size() << " triangles, glb " << fs::file_size(glb)
              << " bytes in " << std::chrono::duration<double>(t1 - t0).count() << " s, wrl "
              << fs::file_size(wrl) << " bytes in "
              << std::chrono::duration<double>(t2 - t1).count() << " s (not asserted)\n";
    ++scenes;
  }
  std::cout << scenes << " scenes written to " << out << "\n";
  EXPECT_GE(scenes, 10);
}

}  // namespace
}  // namespace facets
