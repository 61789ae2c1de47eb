// Issue 6, start values: the start surface fitted to the tie points against the start
// plane on the built-up block scene (scenes/data/block.json: terrain waves up to 1.2 m,
// five buildings 4-12 m high, 400 tie points), both at the coarsest level's node spacing
// of a 3-level run. Only the tie points are needed: no images are rendered.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "engine/start/start_tiepoints.h"
#include "mesh/tessellation.h"
#include "scenes/camera_layout.h"
#include "scenes/evaluate.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"

namespace facets {
namespace {

MeshData ToMeshData(const TinMesh& mesh) {
  MeshData data;
  for (auto vh : mesh.vertices()) data.vertices.push_back(ToEigen(mesh.point(vh)));
  for (auto fh : mesh.faces()) {
    Eigen::Vector3i f;
    int k = 0;
    for (auto vh : mesh.fv_range(fh)) f[k++] = vh.idx();
    data.faces.push_back(f);
  }
  return data;
}

TEST(StartTiePoints, BlockSceneCloserThanThePlane) {
  const Scene scene = LoadScene(std::string(FACETS_SOURCE_DIR) + "/scenes/data/block.json");
  const TruthMesh truth = BuildTruthMesh(scene);
  const Renderer renderer(scene, truth);
  ImageBlock block = BuildImageBlock(scene);
  SampleTiePoints(scene, truth, renderer, static_cast<uint32_t>(scene.seed), &block);
  const RegionOfInterest& roi = scene.roi;
  MeshData truth_data;
  truth_data.vertices = truth.vertices;
  truth_data.faces = truth.faces;

  // Coarsest level of 3: edge = 4 grey facets x 2 pixels x 4 ground pixels.
  const double spacing = kSubdivisions * 2.0 * scene.ground_pixel_size * 4.0;
  std::vector<Eigen::Vector3d> points = TiePointsInRegion(block, roi);
  std::vector<double> z;
  for (const auto& p : points) z.push_back(p.z());
  std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
  const double median = z[z.size() / 2];  // the plane start's height (no mean terrain height)

  StartGridOptions plane;
  plane.min = roi.min.head<2>();
  plane.max = roi.max.head<2>();
  plane.spacing = spacing;
  plane.plane_height = median;
  auto truth_z = [&](double x, double y) {
    return renderer.Cast(Eigen::Vector3d(x, y, 1000.0), Eigen::Vector3d(0, 0, -1)).point.z();
  };
  // rms of the start surface against the truth on a 0.5 m grid (a TIN of 3.84 m edges
  // cannot follow a wall: see the ideal below), and at its nodes alone.
  auto rms = [&](const TinMesh& start) {
    return EvaluateHeights(truth_data, ToMeshData(start), roi, 0.5, 0.0).rms;
  };
  auto rms_nodes = [&](const TinMesh& start) {
    double sum = 0.0;
    for (auto vh : start.vertices()) {
      const auto p = start.point(vh);
      sum += std::pow(p[2] - truth_z(p[0], p[1]), 2);
    }
    return std::sqrt(sum / start.n_vertices());
  };
  const TinMesh plane_start = MakeStartGrid(plane);
  const double rms_plane = rms(plane_start);
  TiePointStartReport report;
  const TinMesh fitted_start = StartFromTiePoints(points, roi, spacing, {}, &report);
  const double rms_fitted = rms(fitted_start);
  StartGridOptions ideal = plane;
  ideal.height = truth_z;  // the truth at the nodes: the best a start TIN of this spacing does
  const double rms_ideal = rms(MakeStartGrid(ideal));

  // The same with every tenth point a blunder of 4-30 m up or down.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> blunder(4, 30);
  for (size_t i = 9; i < points.size(); i += 10) points[i].z() += (i % 20 == 19 ? -1 : 1) * blunder(rng);
  const double rms_blunders = rms(StartFromTiePoints(points, roi, spacing));

  std::cout << points.size() << " tie points in the ROI, node spacing " << spacing << " m\n"
            << "start plane at " << median << " m: rms " << rms_plane << " m, at the nodes "
            << rms_nodes(plane_start) << " m\n"
            << "tie-point start: rms " << rms_fitted << " m, at the nodes " << rms_nodes(fitted_start)
            << " m (" << report.Brief() << ")\n"
            << "truth at the nodes: rms " << rms_ideal << " m\n"
            << "tie-point start with 10% blunders: rms " << rms_blunders << " m\n";
  EXPECT_GE(points.size(), 300u);
  // Measured: plane 3.40 m, fitted 2.07 m, truth at the nodes 1.30 m, with blunders 2.00 m.
  EXPECT_LT(rms_fitted, 0.75 * rms_plane);
  EXPECT_LT(rms_blunders, 1.15 * rms_fitted);
}

}  // namespace
}  // namespace facets
