// End-to-end: the held-out view measure (scenes/holdout.h) ranks meshes of the rendered
// oblique block by their true error. The meshes are the renderer's truth and the truth
// displaced along its normals by 0.5 and 2 ground pixels (GSD, 0.12 m); the held-out
// images are the default every 5th, the other 17 colour the mesh. The test also writes
// the truth displaced by 1 GSD and a 2.5D DSM of the truth (walls as drapes between
// 2 GSD height posts) to $TEST_TMPDIR/holdout_variants/ for the table in
// docs/EXPERIMENTS.md ("Held-out views").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "io/ply_io.h"
#include "scenes/holdout.h"
#include "scenes/truth_mesh.h"
#include "tests/rendered_scene.h"
#include "visibility/embree_scene.h"

namespace facets {
namespace {
namespace fs = std::filesystem;

std::string TempDir() {
  const char* tmp = std::getenv("TEST_TMPDIR");
  return std::string(tmp && *tmp ? tmp : "/tmp") + "/facets_holdout_test";
}

// The mesh with every vertex moved by `distance` (m) along the mean normal of the faces
// around its position (area-weighted; vertices at one position, 0.01 mm apart at most,
// move together, so walls and roofs stay joined). Vertices of no face stay.
MeshData Displaced(const MeshData& mesh, double distance) {
  using Key = std::tuple<long long, long long, long long>;
  auto key = [](const Eigen::Vector3d& p) {
    return Key{std::llround(p.x() * 1e5), std::llround(p.y() * 1e5), std::llround(p.z() * 1e5)};
  };
  std::map<Key, Eigen::Vector3d> normal_at;
  for (const Eigen::Vector3i& f : mesh.faces) {
    const Eigen::Vector3d n = (mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]);
    for (int k = 0; k < 3; ++k) normal_at[key(mesh.vertices[f[k]])] += n;
  }
  MeshData moved = mesh;
  moved.normals.clear();
  for (Eigen::Vector3d& v : moved.vertices) {
    const auto it = normal_at.find(key(v));
    if (it != normal_at.end() && it->second.norm() > 0.0) v += distance * it->second.normalized();
  }
  return moved;
}

// A 2.5D surface model of `mesh` over the region's XY: heights of the first hit from
// above at posts `spacing` apart, two triangles per cell (walls become steep drapes).
MeshData HeightGrid(const MeshData& mesh, const RegionOfInterest& roi, double spacing) {
  const TriangleScene scene(EmbreeDevice::Shared(), mesh.vertices, mesh.faces);
  const int nx = static_cast<int>(std::floor((roi.max.x() - roi.min.x()) / spacing)) + 1;
  const int ny = static_cast<int>(std::floor((roi.max.y() - roi.min.y()) / spacing)) + 1;
  MeshData grid;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const Eigen::Vector3d top(roi.min.x() + i * spacing, roi.min.y() + j * spacing, roi.max.z() + 100.0);
      const RayHit hit = scene.Intersect(top, Eigen::Vector3d(0, 0, -1));
      const double z = hit.hit ? top.z() - hit.distance : roi.min.z();
      grid.vertices.emplace_back(top.x(), top.y(), z);
    }
  }
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      grid.faces.push_back({a, b, d});
      grid.faces.push_back({a, d, c});
    }
  }
  return grid;
}

double HeldOutZnccMedian(const RenderedScene& rendered, const MeshData& mesh, const std::string& name) {
  HoldoutOptions options;
  options.roi = rendered.scene.roi;
  HoldoutReport report = EvaluateHoldout(rendered.block, mesh.vertices, mesh.faces, options);
  report.mesh_name = name;
  std::cout << report.Table();
  return report.zncc_median;
}

TEST(HoldoutRankingTest, TruthScoresAboveHalfAndTwoGsdDisplaced) {
  const RenderedScene rendered = RenderAndRead("scenes/data/block_oblique.json");
  const double gsd = rendered.scene.ground_pixel_size;
  const MeshData truth = BuildTruthMesh(rendered.scene).ToMeshData();
  const MeshData half = Displaced(truth, 0.5 * gsd);
  const MeshData two = Displaced(truth, 2.0 * gsd);
  for (const MeshData* mesh : {&half, &two}) {
    for (const Eigen::Vector3d& v : mesh->vertices) ASSERT_TRUE(v.allFinite());
  }
  const std::string variants = TempDir() + "/holdout_variants";
  fs::create_directories(variants);
  WritePly(variants + "/truth.ply", truth);
  WritePly(variants + "/displaced_0.5gsd.ply", half);
  WritePly(variants + "/displaced_1gsd.ply", Displaced(truth, gsd));
  WritePly(variants + "/displaced_2gsd.ply", two);
  WritePly(variants + "/dsm_2gsd.ply", HeightGrid(truth, rendered.scene.roi, 2.0 * gsd));
  const double truth_score = HeldOutZnccMedian(rendered, truth, "truth");
  const double half_score = HeldOutZnccMedian(rendered, half, "truth + 0.5 GSD");
  const double two_score = HeldOutZnccMedian(rendered, two, "truth + 2 GSD");
  EXPECT_GT(truth_score, half_score);
  EXPECT_GT(half_score, two_score);
}

}  // namespace
}  // namespace facets
