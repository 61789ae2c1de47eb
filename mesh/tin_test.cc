#include "mesh/tin.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace facets {
namespace {

TEST(StartGrid, PlaneCountsAndNormals) {
  StartGridOptions opt;
  opt.min = Eigen::Vector2d(-2, 1);
  opt.max = Eigen::Vector2d(2, 4);
  opt.spacing = 0.5;
  opt.plane_height = 7.5;
  const TinMesh mesh = MakeStartGrid(opt);
  std::cout << "grid 8x6 cells: " << mesh.n_vertices() << " vertices, " << mesh.n_faces()
            << " faces\n";
  EXPECT_EQ(mesh.n_vertices(), 9u * 7u);
  EXPECT_EQ(mesh.n_faces(), 2u * 8u * 6u);
  for (auto v : mesh.vertices()) {
    EXPECT_EQ(mesh.point(v)[2], 7.5);
    EXPECT_NEAR(mesh.normal(v)[2], 1.0, 1e-15);
  }
  for (auto f : mesh.faces()) EXPECT_GT(mesh.normal(f)[2], 0.999);
}

TEST(StartGrid, HeightFunctionAndMeanNormals) {
  StartGridOptions opt;
  opt.spacing = 0.1;
  opt.height = [](double x, double y) { return 0.5 * x + 0.25 * y; };
  const TinMesh mesh = MakeStartGrid(opt);
  const Eigen::Vector3d n = Eigen::Vector3d(-0.5, -0.25, 1).normalized();
  double max_err = 0;
  for (auto v : mesh.vertices()) {
    const auto p = mesh.point(v);
    EXPECT_NEAR(p[2], 0.5 * p[0] + 0.25 * p[1], 1e-15);
    max_err = std::max(max_err, (ToEigen(mesh.normal(v)) - n).norm());
  }
  EXPECT_LT(max_err, 1e-14);
}

TEST(StartGrid, CheckRejectsBadOptions) {
  StartGridOptions opt;
  opt.spacing = -1;
  EXPECT_THROW(opt.Check(), std::invalid_argument);
  opt.spacing = 0.1;
  opt.max = Eigen::Vector2d(-1, 2);
  EXPECT_THROW(MakeStartGrid(opt), std::invalid_argument);
}

TEST(StartMesh, ReadsObjAndPly) {
  const auto dir = std::filesystem::temp_directory_path() / "facets_mesh_test";
  std::filesystem::create_directories(dir);
  const std::string obj = (dir / "tetra.obj").string();
  {
    std::ofstream out(obj);
    out << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
  }
  const TinMesh tetra = LoadStartMesh(obj);
  EXPECT_EQ(tetra.n_vertices(), 4u);
  EXPECT_EQ(tetra.n_faces(), 4u);
  EXPECT_EQ(tetra.n_edges(), 6u);
  // Closed, outward oriented: normals point away from the centroid.
  for (auto v : tetra.vertices()) {
    EXPECT_GT((tetra.point(v) - TinMesh::Point(0.25, 0.25, 0.25)) | tetra.normal(v), 0.0);
  }
  const std::string ply = (dir / "quad.ply").string();
  {
    std::ofstream out(ply);
    out << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
           "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
           "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
  }
  const TinMesh quad = LoadStartMesh(ply);
  EXPECT_EQ(quad.n_faces(), 2u);  // polygon triangulated
  std::filesystem::remove_all(dir);
}

TEST(StartMesh, ErrorsNameTheFile) {
  try {
    LoadStartMesh("/nonexistent/start.ply");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/start.ply"), std::string::npos);
  }
  const auto path = (std::filesystem::temp_directory_path() / "facets_bad_mesh.xyz").string();
  { std::ofstream(path) << "not a mesh\n"; }
  try {
    LoadStartMesh(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    std::cout << "error: " << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace facets
