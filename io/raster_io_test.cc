#include "io/raster_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace facets {
namespace {
namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("facets_raster_io_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

RasterGrid SmallGrid() {
  RasterGrid grid;
  grid.x0 = -12.0;
  grid.y0 = 12.0;
  grid.pixel_size = 0.24;
  grid.width = 300;  // more than one 256-tile: exercises the tiled path
  grid.height = 270;
  return grid;
}

TEST(RasterGridTest, PixelCentreAndCovering) {
  const RasterGrid grid = SmallGrid();
  EXPECT_DOUBLE_EQ(grid.PixelCentre(0, 0).x(), -11.88);
  EXPECT_DOUBLE_EQ(grid.PixelCentre(0, 0).y(), 11.88);
  EXPECT_DOUBLE_EQ(grid.PixelCentre(1, 2).y(), 12.0 - 2.5 * 0.24);

  const RasterGrid cover = RasterGrid::Covering({-12, -12}, {12, 12}, 0.24);
  std::cout << "Covering(-12..12, 0.24): x0 " << cover.x0 << " y0 " << cover.y0 << " "
            << cover.width << " x " << cover.height << "\n";
  EXPECT_EQ(cover.width, 100);
  EXPECT_EQ(cover.height, 100);
  EXPECT_NEAR(cover.x0, -12.0, 1e-12);
  EXPECT_NEAR(cover.y0, 12.0, 1e-12);
  // A corner off the lattice snaps outward.
  const RasterGrid snapped = RasterGrid::Covering({-0.1, 0.05}, {1.01, 0.3}, 0.5);
  EXPECT_DOUBLE_EQ(snapped.x0, -0.5);
  EXPECT_DOUBLE_EQ(snapped.y0, 0.5);
  EXPECT_EQ(snapped.width, 4);   // -0.5 .. 1.5
  EXPECT_EQ(snapped.height, 1);  // 0 .. 0.5
  EXPECT_THROW(RasterGrid::Covering({0, 0}, {1, 1}, 0.0), std::invalid_argument);
}

TEST(RasterIoTest, GeoTiffWithCrsRoundTrip) {
  const std::string dir = TempDir("crs");
  const std::string path = dir + "/dsm.tif";
  Raster dsm;
  dsm.Allocate(SmallGrid(), 1, RasterType::kFloat32, 0.0f);
  dsm.nodata = -9999.0;
  for (int r = 0; r < dsm.grid.height; ++r) {
    for (int c = 0; c < dsm.grid.width; ++c) dsm.at(0, c, r) = 100.0f + 0.01f * c - 0.02f * r;
  }
  dsm.at(0, 5, 7) = -9999.0f;
  GeoReference geo;
  geo.origin = Eigen::Vector3d(500000.0, 5700000.0, 100.0);
  geo.crs = "EPSG:25832";
  WriteGeoTiff(path, dsm, geo);
  EXPECT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  EXPECT_FALSE(fs::exists(WorldFilePath(path)));  // CRS given: georeferencing inside

  std::string wkt;
  const Raster back = ReadGeoTiff(path, geo.origin, &wkt);
  ASSERT_EQ(back.grid.width, dsm.grid.width);
  ASSERT_EQ(back.grid.height, dsm.grid.height);
  EXPECT_EQ(back.type, RasterType::kFloat32);
  ASSERT_TRUE(back.nodata.has_value());
  EXPECT_EQ(*back.nodata, -9999.0);
  EXPECT_NEAR(back.grid.x0, -12.0, 1e-6);
  EXPECT_NEAR(back.grid.y0, 12.0, 1e-6);
  EXPECT_DOUBLE_EQ(back.grid.pixel_size, 0.24);
  EXPECT_EQ(back.data, dsm.data);  // float32 DEFLATE is lossless: bit-exact
  std::cout << "CRS WKT head: " << wkt.substr(0, 60) << "... (" << fs::file_size(path)
            << " bytes)\n";
  EXPECT_NE(wkt.find("25832"), std::string::npos);
  EXPECT_NE(wkt.find("UTM zone 32N"), std::string::npos);
}

TEST(RasterIoTest, TiffWithWorldFileWhenNoCrs) {
  const std::string dir = TempDir("tfw");
  const std::string path = dir + "/ortho.tif";
  Raster ortho;
  RasterGrid grid = SmallGrid();
  grid.width = 40;
  grid.height = 30;
  ortho.Allocate(grid, 3, RasterType::kUInt8, 0.0f);
  for (int b = 0; b < 3; ++b) {
    for (int r = 0; r < grid.height; ++r) {
      for (int c = 0; c < grid.width; ++c) ortho.at(b, c, r) = 10.4f * b + c + 2.0f * r;
    }
  }
  ortho.at(0, 0, 0) = 300.0f;  // clamped
  ortho.at(1, 0, 0) = -5.0f;   // clamped
  GeoReference geo;
  geo.origin = Eigen::Vector3d(1000.5, 2000.25, 0.0);
  WriteGeoTiff(path, ortho, geo);
  const std::string tfw = WorldFilePath(path);
  ASSERT_TRUE(fs::exists(tfw));
  std::ifstream in(tfw);
  std::stringstream text;
  text << in.rdbuf();
  std::cout << "world file:\n" << text.str();
  EXPECT_EQ(text.str(), "0.24\n0\n0\n-0.24\n988.62\n2012.13\n");

  std::string wkt = "x";
  const Raster back = ReadGeoTiff(path, geo.origin, &wkt);
  EXPECT_TRUE(wkt.empty());
  EXPECT_EQ(back.type, RasterType::kUInt8);
  EXPECT_EQ(back.bands, 3);
  EXPECT_NEAR(back.grid.x0, -12.0, 1e-9);  // from the world file, via GDAL
  EXPECT_NEAR(back.grid.y0, 12.0, 1e-9);
  EXPECT_EQ(back.at(0, 0, 0), 255.0f);
  EXPECT_EQ(back.at(1, 0, 0), 0.0f);
  EXPECT_EQ(back.at(1, 3, 2), std::round(10.4f + 3 + 4));
  EXPECT_EQ(back.at(2, 39, 29), std::round(20.8f + 39 + 58));
}

TEST(RasterIoTest, UInt16RoundTrip) {
  const std::string path = TempDir("u16") + "/sigma.tif";
  Raster r;
  RasterGrid grid = SmallGrid();
  grid.width = 17;
  grid.height = 5;
  r.Allocate(grid, 1, RasterType::kUInt16, 1234.6f);
  r.nodata = 65535;
  WriteGeoTiff(path, r, GeoReference{});
  const Raster back = ReadGeoTiff(path, Eigen::Vector3d::Zero());
  EXPECT_EQ(back.type, RasterType::kUInt16);
  EXPECT_EQ(back.at(0, 16, 4), 1235.0f);
  EXPECT_EQ(*back.nodata, 65535.0);
}

TEST(RasterIoTest, ErrorsNameTheFile) {
  const std::string dir = TempDir("errors");
  Raster r;
  RasterGrid grid = SmallGrid();
  grid.width = 4;
  grid.height = 4;
  r.Allocate(grid, 1, RasterType::kFloat32, 1.0f);

  GeoReference bad_crs;
  bad_crs.crs = "EPSG:999999999";
  try {
    WriteGeoTiff(dir + "/a.tif", r, bad_crs);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    std::cout << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find("a.tif"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("CRS"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(dir + "/a.tif"));
  EXPECT_FALSE(fs::exists(dir + "/a.tif.tmp"));

  try {
    WriteGeoTiff(dir + "/missing_dir/b.tif", r, GeoReference{});
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    std::cout << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find("b.tif"), std::string::npos);
  }

  Raster wrong = r;
  wrong.data.pop_back();
  EXPECT_THROW(WriteGeoTiff(dir + "/c.tif", wrong, GeoReference{}), std::invalid_argument);
  Raster bad_nodata = r;
  bad_nodata.type = RasterType::kUInt8;
  bad_nodata.nodata = -9999;
  EXPECT_THROW(WriteGeoTiff(dir + "/d.tif", bad_nodata, GeoReference{}), std::invalid_argument);
  RasterWriteOptions opts;
  opts.compression = "JPEG2000";
  EXPECT_THROW(WriteGeoTiff(dir + "/e.tif", r, GeoReference{}, opts), std::invalid_argument);

  try {
    ReadGeoTiff(dir + "/nothing.tif", Eigen::Vector3d::Zero());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nothing.tif"), std::string::npos);
  }
}

}  // namespace
}  // namespace facets
