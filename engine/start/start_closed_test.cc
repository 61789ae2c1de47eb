#include "engine/start/start_closed.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "io/ply_io.h"
#include "mesh/tessellation.h"

namespace facets {
namespace {

// A start mesh from elsewhere with a triangle of no area: a curved 3 x 3 grid of 1 m
// whose middle vertex lies on the segment between two of its ring neighbours (what
// snapping a TIN's vertices onto a straight eave does: 13 such triangles in a level-1
// TIN snapped to the block's truth made `facets reconstruct --start-mesh` stop with
// "tessellation point 75 is not finite", docs/EXPERIMENTS.md session 11).
MeshData GridWithACap() {
  MeshData data;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) data.vertices.emplace_back(i, j, 0.3 * i * i + 0.1 * j);  // curved
  }
  data.vertices[4] = 0.5 * (data.vertices[1] + data.vertices[5]);  // on (1, 0) - (2, 1)
  for (int j = 0; j < 2; ++j) {
    for (int i = 0; i < 2; ++i) {
      const int a = 3 * j + i;
      data.faces.emplace_back(a, a + 1, a + 4);
      data.faces.emplace_back(a, a + 4, a + 3);
    }
  }
  return data;
}

bool AllFinite(const Tessellation& t) {
  for (const auto& p : t.points) {
    if (!p.allFinite()) return false;
  }
  return true;
}

TEST(ClosedStart, GivenMeshWithATriangleOfNoAreaIsRepaired) {
  const std::string file = testing::TempDir() + "/facets_start_with_cap.ply";
  const MeshData data = GridWithACap();
  WritePly(file, data);

  ClosedStartOptions options;
  options.mesh_file = file;
  const ClosedStart start = PrepareClosedStart(ImageBlock{}, RegionOfInterest{}, options);
  EXPECT_EQ(start.given_repair.degenerate, 1);
  EXPECT_EQ(start.given_repair.flipped, 1);
  EXPECT_EQ(start.given_repair.left, 0);
  EXPECT_NE(start.Describe().find("1 triangles of no area repaired"), std::string::npos) << start.Describe();
  const TinMesh mesh = MakeClosedStartMesh(start, options, 0.5, {}, AdjustmentOptions{}, nullptr, {});
  EXPECT_GT(mesh.n_faces(), 8u);  // the quality pass split the 1 m edges
  EXPECT_TRUE(AllFinite(Tessellate(mesh)));
  std::filesystem::remove(file);
}

TEST(ClosedStart, GivenMeshOfOneFlatTriangleIsAnErrorNamingTheFile) {
  const std::string file = testing::TempDir() + "/facets_start_flat.ply";
  MeshData data;
  data.vertices = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(1, 0, 0)};
  data.faces = {Eigen::Vector3i(0, 1, 2)};
  WritePly(file, data);
  ClosedStartOptions options;
  options.mesh_file = file;
  try {
    PrepareClosedStart(ImageBlock{}, RegionOfInterest{}, options);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file), std::string::npos) << what;
    EXPECT_NE(what.find("1 triangles of no area"), std::string::npos) << what;
  }
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace facets
