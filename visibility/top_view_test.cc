#include "visibility/top_view.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <stdexcept>

#include "visibility/test_util.h"

namespace facets {
namespace {

RasterGrid Grid(double x0, double y0, double pixel, int w, int h) {
  RasterGrid g;
  g.x0 = x0;
  g.y0 = y0;
  g.pixel_size = pixel;
  g.width = w;
  g.height = h;
  return g;
}

// A sloped plane is reproduced exactly: heights, and any linear per-node function
// (linear on every facet) interpolated on the facet hit.
TEST(TopViewTest, SlopedPlaneIsExact) {
  FlatMesh mesh;
  auto height = [](double x, double y) { return 3.0 + 0.2 * x - 0.35 * y; };
  AppendGridForTesting(-10, -10, 10, 10, 7, 5, height, &mesh);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  SurfaceScene scene(tess);
  const RasterGrid grid = Grid(-9.0, 9.0, 0.13, 138, 138);
  const TopView top = CastTopView(scene, tess, grid);
  EXPECT_EQ(top.stats.hits, grid.NumPixels());
  EXPECT_EQ(top.stats.misses, 0);
  EXPECT_EQ(top.stats.back_faces, 0);

  std::vector<double> grey(tess.points.size() * 2), sigma(tess.points.size());
  for (size_t k = 0; k < tess.points.size(); ++k) {
    const Eigen::Vector3d& p = tess.points[k];
    grey[2 * k] = 100.0 + 5.0 * p.x() + 2.0 * p.y();
    grey[2 * k + 1] = 0.1 * p.z();
    sigma[k] = 0.01 + 0.001 * p.x();
  }
  const Raster dsm = MakeDsm(top);
  const Raster ortho = MakeOrthophoto(top, tess, grey, 2, RasterType::kFloat32);
  const Raster sig = MakeSigmaRaster(top, tess, sigma);
  double max_dz = 0, max_dg = 0, max_ds = 0;
  for (int r = 0; r < grid.height; ++r) {
    for (int c = 0; c < grid.width; ++c) {
      const Eigen::Vector2d xy = grid.PixelCentre(c, r);
      const double z = height(xy.x(), xy.y());
      max_dz = std::max(max_dz, std::abs(top.z[top.Index(c, r)] - z));
      max_dz = std::max(max_dz, std::abs(dsm.at(0, c, r) - z) - 1e-5);  // float32 file
      max_dg =
          std::max(max_dg, std::abs(ortho.at(0, c, r) - (100.0 + 5.0 * xy.x() + 2.0 * xy.y())));
      max_dg = std::max(max_dg, std::abs(ortho.at(1, c, r) - 0.1 * z));
      max_ds = std::max(max_ds, std::abs(sig.at(0, c, r) - (0.01 + 0.001 * xy.x())));
    }
  }
  std::cout << "sloped plane: max |dz| " << max_dz << " m, max |dgrey| " << max_dg
            << ", max |dsigma| " << max_ds << "\n";
  EXPECT_LT(max_dz, 1e-9);
  EXPECT_LT(max_dg, 1e-3);  // float32 storage of values around 100
  EXPECT_LT(max_ds, 1e-7);
}

// A box on the ground: every pixel whose centre lies inside the footprint has the
// roof height, every other one the ground height; the wall leaves no ramp.
TEST(TopViewTest, WallsDoNotSmear) {
  FlatMesh mesh;
  AppendGridForTesting(
      -10, -10, 10, 10, 10, 10, [](double, double) { return 0.0; }, &mesh);
  AppendBoxForTesting({-3.02, -2.0, -1.0}, {4.1, 3.3, 6.0}, false, &mesh);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  SurfaceScene scene(tess);
  const RasterGrid grid = Grid(-8.0, 8.0, 0.1, 160, 160);
  const TopView top = CastTopView(scene, tess, grid);
  std::vector<double> grey(tess.points.size());
  for (size_t k = 0; k < grey.size(); ++k) grey[k] = tess.points[k].z() > 3.0 ? 200.0 : 50.0;
  const Raster ortho = MakeOrthophoto(top, tess, grey);
  int wrong_height = 0, wrong_grey = 0, inside = 0;
  for (int r = 0; r < grid.height; ++r) {
    for (int c = 0; c < grid.width; ++c) {
      const Eigen::Vector2d xy = grid.PixelCentre(c, r);
      const bool in = xy.x() > -3.02 && xy.x() < 4.1 && xy.y() > -2.0 && xy.y() < 3.3;
      inside += in;
      wrong_height += std::abs(top.z[top.Index(c, r)] - (in ? 6.0 : 0.0)) > 1e-9;
      wrong_grey += ortho.at(0, c, r) != (in ? 200.0f : 50.0f);
    }
  }
  std::cout << "box: " << inside << " roof pixels, " << wrong_height << " wrong heights, "
            << wrong_grey << " wrong grey values, " << top.stats.back_faces << " back faces\n";
  EXPECT_EQ(inside, 71 * 53);
  EXPECT_EQ(wrong_height, 0);
  EXPECT_EQ(wrong_grey, 0);
  EXPECT_EQ(top.stats.back_faces, 0);
}

// An open sheet facing down above the ground (a balcony seen only from below).
TEST(TopViewTest, BackFacePolicy) {
  FlatMesh mesh;
  AppendGridForTesting(
      -5, -5, 5, 5, 4, 4, [](double, double) { return 0.0; }, &mesh);
  FlatMesh sheet;
  AppendGridForTesting(
      -1, -1, 1, 1, 1, 1, [](double, double) { return 2.5; }, &sheet);
  const int base = static_cast<int>(mesh.vertices.size());
  for (const auto& v : sheet.vertices) mesh.vertices.push_back(v);
  for (const auto& f : sheet.faces) mesh.faces.emplace_back(base + f[0], base + f[2], base + f[1]);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  SurfaceScene scene(tess);
  const RasterGrid grid = Grid(-4.0, 4.0, 0.25, 32, 32);  // 8 x 8 pixels under the sheet

  const TopView first = CastTopView(scene, tess, grid);
  TopViewOptions skip;
  skip.skip_back_faces = true;
  const TopView through = CastTopView(scene, tess, grid, skip);
  std::cout << "sheet: back faces " << first.stats.back_faces << " (first hit), "
            << through.stats.back_faces << " (skipped)\n";
  EXPECT_EQ(first.stats.back_faces, 64);
  EXPECT_EQ(through.stats.back_faces, 64);
  EXPECT_DOUBLE_EQ(first.z[first.Index(16, 16)], 2.5);
  EXPECT_DOUBLE_EQ(through.z[through.Index(16, 16)], 0.0);
  EXPECT_DOUBLE_EQ(first.z[first.Index(2, 2)], 0.0);
  EXPECT_EQ(through.stats.hits, grid.NumPixels());
}

TEST(TopViewTest, NoDataAndErrors) {
  FlatMesh mesh;
  AppendGridForTesting(
      0, 0, 4, 4, 2, 2, [](double, double) { return 1.0; }, &mesh);
  const Tessellation tess = TessellateFlatForTesting(mesh);
  SurfaceScene scene(tess);
  // Half the grid lies west of the surface.
  const RasterGrid grid = Grid(-2.0, 4.0, 0.5, 8, 8);
  const TopView top = CastTopView(scene, tess, grid);
  EXPECT_EQ(top.stats.hits, 32);
  EXPECT_EQ(top.stats.misses, 32);
  const Raster dsm = MakeDsm(top);
  EXPECT_EQ(dsm.at(0, 0, 0), kDsmNoData);
  EXPECT_EQ(dsm.at(0, 7, 7), 1.0f);
  ASSERT_TRUE(dsm.nodata.has_value());
  EXPECT_EQ(*dsm.nodata, kDsmNoData);

  // Grey 0 on the surface must not read as nodata 0; NaN sigma gives nodata.
  std::vector<double> grey(tess.points.size(), 0.0);
  const Raster ortho = MakeOrthophoto(top, tess, grey);
  EXPECT_EQ(ortho.at(0, 0, 0), 0.0f);
  EXPECT_EQ(ortho.at(0, 7, 7), 1.0f);
  std::vector<double> sigma(tess.points.size(), std::nan(""));
  EXPECT_EQ(MakeSigmaRaster(top, tess, sigma).at(0, 7, 7), kDsmNoData);

  EXPECT_THROW(MakeOrthophoto(top, tess, std::vector<double>(3, 0.0)), std::invalid_argument);
  FlatMesh other;
  AppendGridForTesting(
      0, 0, 4, 4, 3, 3, [](double, double) { return 1.0; }, &other);
  const Tessellation other_tess = TessellateFlatForTesting(other);
  EXPECT_THROW(CastTopView(scene, other_tess, grid), std::invalid_argument);
  TopViewOptions bad;
  bad.start_margin = 0;
  EXPECT_THROW(CastTopView(scene, tess, grid, bad), std::invalid_argument);
}

}  // namespace
}  // namespace facets
