// End-to-end: true orthophoto, DSM and sigma raster from a 3D surface (issue 8, part
// 4). The "reconstruction" is built from the truth, exactly what a perfect adjustment
// would produce: a 2 m TIN on the truth heights, tessellated with creases, object grey
// values = the noise-free synthetic radiance at every grey node. Its top view is
// compared with the truth rendered from above at the raster's pixel centres.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "io/raster_io.h"
#include "mesh/creases.h"
#include "mesh/tessellation.h"
#include "mesh/tin.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"
#include "visibility/surface_scene.h"
#include "visibility/test_util.h"
#include "visibility/top_view.h"

namespace facets {
namespace {
namespace fs = std::filesystem;

std::string SceneFile(const std::string& name) {
  return std::string(FACETS_SOURCE_DIR) + "/scenes/data/" + name;
}

SurfaceHit CastDown(const Renderer& renderer, double x, double y) {
  return renderer.Cast(Eigen::Vector3d(x, y, 1000.0), Eigen::Vector3d(0, 0, -1));
}

// Radiance of every grey node, seen from above. Nodes on a crease exist once per side;
// each is shaded with the truth face on its own side: the vertical ray is moved 1 mm
// from the node towards the mean centroid of the facets that use it.
std::vector<double> NodeRadiance(const Tessellation& tess, const Renderer& renderer) {
  std::vector<Eigen::Vector2d> centroid_sum(tess.points.size(), Eigen::Vector2d::Zero());
  std::vector<int> count(tess.points.size(), 0);
  for (const Eigen::Vector3i& t : tess.triangles) {
    const Eigen::Vector2d c =
        (tess.points[t[0]] + tess.points[t[1]] + tess.points[t[2]]).head<2>() / 3.0;
    for (int k = 0; k < 3; ++k) {
      centroid_sum[t[k]] += c;
      ++count[t[k]];
    }
  }
  std::vector<double> grey(tess.points.size(), 0.0);
  for (size_t k = 0; k < tess.points.size(); ++k) {
    Eigen::Vector2d xy = tess.points[k].head<2>();
    if (count[k] > 0) {
      const Eigen::Vector2d toward = centroid_sum[k] / count[k] - xy;
      if (toward.norm() > 1e-9) xy += 1e-3 * toward.normalized();
    }
    grey[k] = renderer.Radiance(CastDown(renderer, xy.x(), xy.y()));
  }
  return grey;
}

TEST(ProductsTest, SeedGableOrthophotoAndDsmMatchTruth) {
  const Scene scene = LoadScene(SceneFile("seed_gable_parallel.json"));
  const TruthMesh truth = BuildTruthMesh(scene);
  const Renderer renderer(scene, truth);

  StartGridOptions grid_options;
  grid_options.min = scene.roi.min.head<2>();
  grid_options.max = scene.roi.max.head<2>();
  grid_options.spacing = 2.0;  // 4x4 grey facets of 0.5 m: about 2x2 pixels of 0.24 m
  grid_options.height = [&](double x, double y) { return CastDown(renderer, x, y).point.z(); };
  const TinMesh mesh = MakeStartGrid(grid_options);
  const CornerNormals corners = ComputeCornerNormals(mesh, 30.0);
  const std::vector<G1Patch> patches = BuildPatches(mesh, corners);
  const Tessellation tess = Tessellate(mesh, patches, corners);
  const std::vector<double> grey = NodeRadiance(tess, renderer);
  std::cout << "TIN " << mesh.n_vertices() << " vertices, " << mesh.n_faces() << " faces, "
            << corners.num_crease_edges << " crease edges; " << tess.points.size()
            << " grey nodes, " << tess.triangles.size() << " facets\n";

  const SurfaceScene surface(tess, /*refittable=*/false);
  const RasterGrid grid = RasterGrid::Covering(scene.roi.min.head<2>(), scene.roi.max.head<2>(),
                                               scene.ground_pixel_size);
  const TopView top = CastTopView(surface, tess, grid);
  const Raster ortho = MakeOrthophoto(top, tess, grey);
  const Raster dsm = MakeDsm(top);
  // Sigma: a per-node field with a known linear trend, to check the third raster.
  std::vector<double> node_sigma(tess.points.size());
  for (size_t k = 0; k < node_sigma.size(); ++k) node_sigma[k] = 0.05 + 0.001 * tess.points[k].x();
  const Raster sigma = MakeSigmaRaster(top, tess, node_sigma);

  double abs_grey = 0, sq_dz = 0, max_dz = 0, max_dgrey = 0, max_dsigma = 0;
  long long n = 0;
  for (int r = 0; r < grid.height; ++r) {
    for (int c = 0; c < grid.width; ++c) {
      const Eigen::Vector2d xy = grid.PixelCentre(c, r);
      const SurfaceHit hit = CastDown(renderer, xy.x(), xy.y());
      if (!scene.roi.Contains(Eigen::Vector3d(xy.x(), xy.y(), hit.point.z()))) continue;
      ASSERT_TRUE(top.Hit(c, r)) << "no surface at pixel " << c << ", " << r;
      const double truth_grey = std::clamp(std::round(renderer.Radiance(hit)), 0.0, 255.0);
      const double dgrey = ortho.at(0, c, r) - truth_grey;
      const double dz = dsm.at(0, c, r) - hit.point.z();
      abs_grey += std::abs(dgrey);
      max_dgrey = std::max(max_dgrey, std::abs(dgrey));
      sq_dz += dz * dz;
      max_dz = std::max(max_dz, std::abs(dz));
      max_dsigma = std::max(max_dsigma, std::abs(sigma.at(0, c, r) - (0.05 + 0.001 * xy.x())));
      ++n;
    }
  }
  const double mae = abs_grey / n, rms = std::sqrt(sq_dz / n);
  std::cout << "seed gable orthophoto " << grid.width << " x " << grid.height << " at "
            << grid.pixel_size << " m, " << n << " pixels in the ROI: MAE " << mae
            << " grey values (max " << max_dgrey << "); DSM rms " << rms << " m (max "
            << max_dz << " m); sigma max error " << max_dsigma << "\n";
  RecordProperty("orthophoto_mae", std::to_string(mae));
  RecordProperty("dsm_rms_m", std::to_string(rms));
  EXPECT_EQ(n, 100LL * 100);
  EXPECT_LT(mae, 3.0);
  EXPECT_LT(rms, 0.1);
  EXPECT_LT(max_dsigma, 1e-6);

  // The three products on disk, georeferenced, and the DSM read back unchanged.
  const std::string dir = testing::TempDir() + "/facets_products_gable";
  fs::remove_all(dir);
  fs::create_directories(dir);
  GeoReference geo;
  geo.origin = Eigen::Vector3d(500000.0, 5700000.0, 50.0);
  geo.crs = "EPSG:25832";
  WriteGeoTiff(dir + "/ortho.tif", ortho, geo);
  WriteGeoTiff(dir + "/dsm.tif", dsm, geo);
  WriteGeoTiff(dir + "/sigma.tif", sigma, geo);
  const Raster dsm_back = ReadGeoTiff(dir + "/dsm.tif", geo.origin);
  EXPECT_EQ(dsm_back.data, dsm.data);
  EXPECT_NEAR(dsm_back.grid.x0, grid.x0, 1e-6);
  EXPECT_NEAR(dsm_back.grid.y0, grid.y0, 1e-6);
  const Raster ortho_back = ReadGeoTiff(dir + "/ortho.tif", geo.origin);
  EXPECT_EQ(ortho_back.type, RasterType::kUInt8);
  EXPECT_EQ(ortho_back.data, ortho.data);
}

// Facades do not smear: the block scene's truth surface (walls, an overhanging wall)
// seen from above. Across a wall the DSM jumps from roof to ground between two
// neighbouring pixels; under the overhang it holds the roof.
TEST(ProductsTest, BlockFacadesDoNotSmear) {
  const Scene scene = LoadScene(SceneFile("block.json"));
  const TruthMesh truth = BuildTruthMesh(scene);
  const Renderer renderer(scene, truth);

  // The two southern buildings: the tall one at (-16, -18) (20 x 12 m, 12 m, south
  // wall leaning 9 degrees outward) and the small one at (18, -16) (10 x 10 m, 4 m).
  const Eigen::Vector2d crop_min(-32, -32), crop_max(30, -6);
  FlatMesh flat;
  flat.vertices = truth.vertices;
  for (const Eigen::Vector3i& f : truth.faces) {
    const Eigen::Vector2d c =
        (truth.vertices[f[0]] + truth.vertices[f[1]] + truth.vertices[f[2]]).head<2>() / 3.0;
    if ((c.array() > crop_min.array() - 2).all() && (c.array() < crop_max.array() + 2).all()) {
      flat.faces.push_back(f);
    }
  }
  const Tessellation tess = TessellateFlatForTesting(flat);
  const SurfaceScene surface(tess, /*refittable=*/false);
  const RasterGrid grid = RasterGrid::Covering(crop_min, crop_max, scene.ground_pixel_size);
  const TopView top = CastTopView(surface, tess, grid);
  const Raster dsm = MakeDsm(top);

  double sq = 0;
  long long n = 0, off = 0;
  for (int r = 0; r < grid.height; ++r) {
    for (int c = 0; c < grid.width; ++c) {
      const Eigen::Vector2d xy = grid.PixelCentre(c, r);
      const SurfaceHit hit = CastDown(renderer, xy.x(), xy.y());
      ASSERT_TRUE(hit.hit && top.Hit(c, r));
      const double dz = dsm.at(0, c, r) - hit.point.z();
      sq += dz * dz;
      off += std::abs(dz) > 0.01;
      ++n;
    }
  }
  std::cout << "block DSM " << grid.width << " x " << grid.height << " at " << grid.pixel_size
            << " m vs truth heights: rms " << std::sqrt(sq / n) << " m, " << off
            << " pixels off by more than 1 cm; back faces " << top.stats.back_faces << "\n";
  EXPECT_LT(std::sqrt(sq / n), 0.01);

  // Profiles across walls: how many pixels lie between ground and roof (a smeared
  // facade would put a ramp there). East wall of the small building (x = 23), and the
  // overhanging south wall of the tall one (foot at y = -24, eaves ~1.9 m further out).
  // Pixels of the DSM profile through `fixed` (a Y when along_x, else an X) between
  // `from` and `to` whose height lies strictly between ground and roof.
  auto ramp_pixels = [&](double fixed, bool along_x, double from, double to, double low,
                         double high) {
    int ramp = 0;
    for (double s = from; s <= to; s += grid.pixel_size) {
      const double x = along_x ? s : fixed, y = along_x ? fixed : s;
      const float z = dsm.at(0, static_cast<int>((x - grid.x0) / grid.pixel_size),
                             static_cast<int>((grid.y0 - y) / grid.pixel_size));
      ramp += z > low + 0.5 && z < high - 0.5;
    }
    return ramp;
  };
  const double ground_east = CastDown(renderer, 25.0, -16.0).point.z();
  const double roof_small = CastDown(renderer, 18.0, -16.0).point.z();
  const int ramp_small = ramp_pixels(-16.0, true, 21.0, 25.0, ground_east, roof_small);
  const double ground_south = CastDown(renderer, -16.0, -30.0).point.z();
  const double roof_tall = CastDown(renderer, -16.0, -18.0).point.z();
  const int ramp_tall = ramp_pixels(-16.0, false, -30.0, -20.0, ground_south, roof_tall);
  // Under the overhang (0.5 m and 1.5 m outside the wall foot) the DSM holds the roof.
  auto dsm_at = [&](double x, double y) {
    return dsm.at(0, static_cast<int>((x - grid.x0) / grid.pixel_size),
                  static_cast<int>((grid.y0 - y) / grid.pixel_size));
  };
  const double under_overhang_1 = dsm_at(-16.0, -24.5), under_overhang_2 = dsm_at(-16.0, -25.5);
  std::cout << "small building: ground " << ground_east << " m, roof " << roof_small
            << " m, ramp pixels across the east wall " << ramp_small << "\n"
            << "tall building: ground " << ground_south << " m, roof " << roof_tall
            << " m, ramp pixels across the overhanging south wall " << ramp_tall
            << "; DSM 0.5 m / 1.5 m outside the wall foot " << under_overhang_1 << " / "
            << under_overhang_2 << " m\n";
  EXPECT_GT(roof_small - ground_east, 3.0);
  EXPECT_LE(ramp_small, 1);
  EXPECT_LE(ramp_tall, 1);
  EXPECT_NEAR(under_overhang_1, roof_tall, 0.05);
  EXPECT_NEAR(under_overhang_2, roof_tall, 0.05);
}

}  // namespace
}  // namespace facets
