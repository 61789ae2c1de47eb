#include "mesh/windows.h"

#include <gtest/gtest.h>

#include <set>

namespace facets {
namespace {

TinMesh Grid(double size, double spacing) {
  StartGridOptions grid;
  grid.min = Eigen::Vector2d(0, 0);
  grid.max = Eigen::Vector2d(size, size);
  grid.spacing = spacing;
  grid.height = [](double x, double y) { return 0.1 * x + 0.05 * y * y; };
  return MakeStartGrid(grid);
}

TEST(Windows, EveryFaceInOneCoreEveryVertexOwnedOnce) {
  const TinMesh mesh = Grid(20.0, 0.5);  // 41 x 41 points, 3200 faces
  ASSERT_EQ(mesh.n_faces(), 3200u);
  WindowPartitionOptions options;
  options.max_faces = 300;
  const auto windows = PartitionIntoWindows(mesh, options);
  // Median halving of 3200 faces down to <= 300: 16 windows of 200.
  ASSERT_EQ(windows.size(), 16u);
  std::vector<int> core_count(mesh.n_faces(), 0), owner_count(mesh.n_vertices(), 0);
  for (const auto& w : windows) {
    EXPECT_EQ(w.core_faces.size(), 200u);
    for (int f : w.core_faces) ++core_count[f];
    for (int v : w.owned_vertices) ++owner_count[v];
    // The margin holds the core and grows it.
    std::set<int> all(w.faces.begin(), w.faces.end());
    for (int f : w.core_faces) EXPECT_TRUE(all.count(f));
    EXPECT_GT(w.faces.size(), w.core_faces.size());
  }
  for (int c : core_count) EXPECT_EQ(c, 1);
  for (int c : owner_count) EXPECT_EQ(c, 1);
}

TEST(Windows, OwnedVerticesAreFreeWithCompleteRings) {
  const TinMesh mesh = Grid(20.0, 0.5);
  WindowPartitionOptions options;
  options.max_faces = 300;
  options.margin_rings = 2;
  for (const auto& w : PartitionIntoWindows(mesh, options)) {
    const WindowMesh wm = ExtractWindowMesh(mesh, w);
    ASSERT_EQ(wm.mesh.n_faces(), w.faces.size());
    ASSERT_EQ(wm.owned_local.size(), w.owned_vertices.size());
    for (int local : wm.owned_local) {
      EXPECT_FALSE(wm.fixed[local]);
      const auto lh = wm.mesh.vertex_handle(local);
      const auto gh = mesh.vertex_handle(wm.global_vertex[local]);
      // Same valence: the whole 1-ring is in the window.
      EXPECT_EQ(wm.mesh.valence(lh), mesh.valence(gh));
      EXPECT_EQ((wm.mesh.point(lh) - mesh.point(gh)).norm(), 0.0);
    }
    // Fixed vertices are exactly those with a face outside the window, and they lie on
    // the window's boundary (unless the level's mesh ends there too).
    int fixed = 0;
    for (size_t v = 0; v < wm.fixed.size(); ++v) {
      if (!wm.fixed[v]) continue;
      ++fixed;
      EXPECT_TRUE(wm.mesh.is_boundary(wm.mesh.vertex_handle(static_cast<int>(v))));
    }
    EXPECT_GT(fixed, 0);
  }
}

TEST(Windows, GroupsShareNoVertex) {
  const TinMesh mesh = Grid(20.0, 0.5);
  WindowPartitionOptions options;
  options.max_faces = 100;
  const auto windows = PartitionIntoWindows(mesh, options);
  const auto groups = IndependentWindowGroups(mesh, windows);
  size_t total = 0;
  for (const auto& group : groups) {
    total += group.size();
    std::vector<int> user(mesh.n_vertices(), -1);
    for (int w : group) {
      for (int f : windows[w].faces) {
        for (auto vh : mesh.fv_range(mesh.face_handle(f))) {
          EXPECT_TRUE(user[vh.idx()] < 0 || user[vh.idx()] == w);
          user[vh.idx()] = w;
        }
      }
    }
  }
  EXPECT_EQ(total, windows.size());
  // Several windows per group on average: there is something to run in parallel.
  EXPECT_LT(groups.size() * 2, windows.size());
}

TEST(Windows, SmallMeshIsOneWindowWithoutFixedVertices) {
  const TinMesh mesh = Grid(4.0, 1.0);
  const auto windows = PartitionIntoWindows(mesh, {});
  ASSERT_EQ(windows.size(), 1u);
  const WindowMesh wm = ExtractWindowMesh(mesh, windows[0]);
  for (bool f : wm.fixed) EXPECT_FALSE(f);
  EXPECT_EQ(wm.owned_local.size(), mesh.n_vertices());
}

}  // namespace
}  // namespace facets
