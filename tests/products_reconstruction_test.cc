// Acceptance of the orthophoto and DSM on a RECONSTRUCTION (issue 8): the seed
// gable-roof stereo pair is rendered, reconstructed by Reconstruct (three pyramid
// levels, as `scripts/run-default.sh`; about a second), the products are written as `facets
// reconstruct` writes them (WriteProducts, with a UTM-sized origin and a CRS so the
// georeferencing is exercised), read back from the GeoTIFFs and compared at every
// raster pixel centre inside the region of interest with the truth seen from above:
//   orthophoto vs the synthetic albedo * shading (the noise-free radiance, rounded to
//   8 bit as the images are): mean absolute error < 3 grey values;
//   DSM vs the truth heights: rms < 0.1 m.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>

#include "engine/pipeline/products.h"
#include "engine/pipeline/reconstruction.h"
#include "io/colmap_io.h"
#include "io/raster_io.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"

namespace facets {
namespace {
namespace fs = std::filesystem;

TEST(ProductsReconstruction, SeedGableOrthophotoAndDsmMatchTruth) {
  const Scene scene =
      LoadScene(std::string(FACETS_SOURCE_DIR) + "/scenes/data/seed_gable_parallel.json");
  const std::string dir = testing::TempDir() + "/facets_products_reconstruction_gable";
  RenderScene(scene, dir + "/scene");
  ImageBlock block = ReadColmapModel(dir + "/scene/sparse", dir + "/scene/images");
  block.roi = scene.roi;
  // Georeference only (cameras and surface stay in the local frame): global = origin +
  // local, so every product must carry the origin for the comparison below to match.
  block.origin = Eigen::Vector3d(500000.0, 5400000.0, 300.0);
  block.crs = "EPSG:25832";

  ReconstructionOptions options;
  options.break_off_gsd = 0.0;  // the break-off in metres of AdjustmentOptions
  options.levels = 3;
  // The plane start this test was written for: from the tie-point start the finest
  // level's first window oscillates (30 iterations, not converged) although its
  // result is closer to the truth (docs/EXPERIMENTS.md, tie-point start).
  options.start = StartSurfaceKind::kPlane;
  options.progress = [](const std::string& line) { std::cout << line << "\n"; };
  Reconstruction r = Reconstruct(block, options);
  ASSERT_FALSE(r.report.levels.empty());
  // Stopped by the break-off or the stall rule (a ridge vertex of one window keeps
  // moving at constant sigma0, tests/reconstruct_test.cc), not by the iteration cap.
  for (const WindowReport& w : r.report.levels.back().windows) {
    EXPECT_TRUE(w.converged || w.stalled);
    EXPECT_LT(w.iterations.size(), static_cast<size_t>(AdjustmentOptions().max_iterations));
  }

  // The scene's ground pixel (what --raster-pixel gives): both rasters and the ROI
  // grid below then lie on one lattice (RasterGrid::Covering snaps to multiples of it).
  const std::string out = dir + "/products";
  fs::remove_all(out);
  ProductOptions products;
  products.raster_pixel = scene.ground_pixel_size;
  WriteProducts(&r, block, out, products);
  std::string crs;
  const Raster ortho = ReadGeoTiff(out + "/ortho.tif", block.origin, &crs);
  const Raster dsm = ReadGeoTiff(out + "/dsm.tif", block.origin);
  EXPECT_NE(crs.find("25832"), std::string::npos) << crs;
  ASSERT_EQ(ortho.grid.width, dsm.grid.width);
  ASSERT_EQ(ortho.grid.height, dsm.grid.height);
  const double s = ortho.grid.pixel_size;
  EXPECT_NEAR(s, scene.ground_pixel_size, 1e-9);

  const double kBorderBand = 0.5;  // m: holes allowed only this close to the ROI edge
  const TruthMesh truth = BuildTruthMesh(scene);
  const Renderer renderer(scene, truth);
  const RasterGrid roi_grid =
      RasterGrid::Covering(scene.roi.min.head<2>(), scene.roi.max.head<2>(), s);
  double abs_grey = 0, sq_dz = 0, max_dz = 0, sum_dgrey = 0;
  long long n = 0, holes = 0, inner_holes = 0;
  for (int roi_row = 0; roi_row < roi_grid.height; ++roi_row) {
    for (int roi_col = 0; roi_col < roi_grid.width; ++roi_col) {
      const Eigen::Vector2d xy = roi_grid.PixelCentre(roi_col, roi_row);
      const SurfaceHit hit =
          renderer.Cast(Eigen::Vector3d(xy.x(), xy.y(), 1000.0), Eigen::Vector3d(0, 0, -1));
      if (!hit.hit || !scene.roi.Contains(hit.point)) continue;
      // The same pixel in the product rasters (same lattice: an integer offset).
      const int col = static_cast<int>(std::lround((xy.x() - ortho.grid.x0) / s - 0.5));
      const int row = static_cast<int>(std::lround((ortho.grid.y0 - xy.y()) / s - 0.5));
      if (col < 0 || row < 0 || col >= ortho.grid.width || row >= ortho.grid.height ||
          ortho.at(0, col, row) == *ortho.nodata || dsm.at(0, col, row) == *dsm.nodata) {
        // No reconstructed surface above this ROI pixel. Expected only in a thin band
        // along the ROI's edge: the TIN's border vertices start on the ROI boundary and
        // move along their surface normals, which on the sloping roof planes have a
        // horizontal component (0.1-0.3 m here), so the surface may end just inside it.
        ++holes;
        const Eigen::Vector2d to_min = xy - scene.roi.min.head<2>();
        const Eigen::Vector2d to_max = scene.roi.max.head<2>() - xy;
        if (std::min(to_min.minCoeff(), to_max.minCoeff()) > kBorderBand) ++inner_holes;
        continue;
      }
      EXPECT_LT((ortho.grid.PixelCentre(col, row) - xy).norm(), 1e-6);
      const double truth_grey = std::clamp(std::round(renderer.Radiance(hit)), 0.0, 255.0);
      const double dgrey = ortho.at(0, col, row) - truth_grey;
      const double dz = dsm.at(0, col, row) - hit.point.z();
      abs_grey += std::abs(dgrey);
      sum_dgrey += dgrey;
      sq_dz += dz * dz;
      max_dz = std::max(max_dz, std::abs(dz));
      ++n;
    }
  }
  ASSERT_GT(n, 0);
  const double mae = abs_grey / n, rms = std::sqrt(sq_dz / n);
  std::cout << "reconstructed seed gable: orthophoto " << ortho.grid.width << " x "
            << ortho.grid.height << " at " << ortho.grid.pixel_size << " m, " << n
            << " ROI pixels with surface (" << holes << " without, " << inner_holes
            << " of them farther than " << kBorderBand << " m inside the ROI edge): MAE " << mae
            << " grey values (mean difference " << sum_dgrey / n << "); DSM rms " << rms
            << " m (max " << max_dz << " m)\n";
  RecordProperty("orthophoto_mae", std::to_string(mae));
  RecordProperty("dsm_rms_m", std::to_string(rms));
  // The ROI is 24 m x 24 m at 0.24 m: 10000 pixels; covered by the surface except
  // at most a border band of two pixels.
  EXPECT_EQ(n + holes, 100LL * 100);
  EXPECT_EQ(inner_holes, 0);
  EXPECT_LT(holes, 4 * 2 * 100);
  EXPECT_LT(mae, 3.0);
  EXPECT_LT(rms, 0.1);
}

}  // namespace
}  // namespace facets
