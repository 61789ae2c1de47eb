// Georeferenced rasters (true orthophoto, DSM, sigma; DESIGN.md section 1 "Out"):
// a north-up grid in local object coordinates, planar float storage, and a GeoTIFF
// writer/reader on GDAL.
//
// Frames: the grid lives in local object coordinates (relative to ImageBlock::origin);
// the files carry global coordinates, global = origin + local. Row 0 is the northern
// row (max Y), column 0 the western one (min X); pixel (col, row) covers
// [x0 + col*s, x0 + (col+1)*s] x [y0 - (row+1)*s, y0 - row*s] and its value belongs to
// its centre (GDAL's "area" pixel interpretation).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace facets {

struct RasterGrid {
  // Local X, Y of the top-left (north-west) CORNER of pixel (0, 0).
  double x0 = 0.0, y0 = 0.0;
  double pixel_size = 1.0;  // object units (m) per pixel, square pixels
  int width = 0, height = 0;

  // Local XY of the centre of pixel (col, row).
  Eigen::Vector2d PixelCentre(int col, int row) const {
    return {x0 + (col + 0.5) * pixel_size, y0 - (row + 0.5) * pixel_size};
  }
  long long NumPixels() const { return static_cast<long long>(width) * height; }
  // Throws std::invalid_argument on a non-positive / non-finite size or coordinate.
  void Check() const;

  // The smallest grid of the given pixel size that covers [min, max] (local XY), with
  // its corner snapped to a multiple of pixel_size, so that rasters of one job made
  // from different windows share one lattice.
  static RasterGrid Covering(const Eigen::Vector2d& min, const Eigen::Vector2d& max,
                             double pixel_size);
};

enum class RasterType { kUInt8, kUInt16, kFloat32 };

// Planar (band-major) raster: value of band b at (col, row) is
// data[(b * height + row) * width + col]. Values are kept as float whatever the file
// type; 8/16-bit types are rounded and clamped when written.
struct Raster {
  RasterGrid grid;
  int bands = 1;
  RasterType type = RasterType::kFloat32;
  // Value of pixels without data (no surface below them). Recorded in the file.
  std::optional<double> nodata;
  std::vector<float> data;

  float& at(int band, int col, int row) {
    return data[(static_cast<size_t>(band) * grid.height + row) * grid.width + col];
  }
  float at(int band, int col, int row) const {
    return data[(static_cast<size_t>(band) * grid.height + row) * grid.width + col];
  }
  // Sized grid.NumPixels() * bands, filled with fill.
  void Allocate(const RasterGrid& g, int num_bands, RasterType t, float fill);
};

// Where the local frame sits on the earth.
struct GeoReference {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // global = origin + local
  // Anything OGRSpatialReference::SetFromUserInput accepts ("EPSG:25832", WKT, PROJ
  // string); "" = unknown.
  std::string crs;
};

struct RasterWriteOptions {
  // 256 x 256 tiles: GDAL's default block for tiled GeoTIFF, what viewers read fast.
  int tile_size = 256;
  // DEFLATE is lossless and read by every GeoTIFF reader (LZW is older, ZSTD not
  // everywhere). Float data gets predictor 3, integer data predictor 2: both shrink
  // smooth surfaces (DSMs) by about half again.
  std::string compression = "DEFLATE";

  // Throws std::invalid_argument on a tile size that is not a positive multiple of 16
  // (a TIFF rule) or an unknown compression.
  void Check() const;
};

// Writes a tiled, compressed TIFF (GDAL GTiff driver). With a CRS: a GeoTIFF carrying
// the CRS and the geotransform. Without one: the TIFF has no geokeys and a world file
// next to it (path with the extension replaced by ".tfw": pixel size, 0, 0, -pixel
// size, global X and Y of the centre of the top-left pixel) holds the georeferencing.
// Every file is written to a unique temporary name first and renamed at the end
// (io/atomic_file.h). Throws
// std::runtime_error / std::invalid_argument naming the file on a bad raster, an
// unknown CRS or a failed write.
void WriteGeoTiff(const std::string& path, const Raster& raster, const GeoReference& geo,
                  const RasterWriteOptions& options = {});

// World file content for a grid (six lines, classic locale, shortest exact decimals).
std::string WorldFileText(const RasterGrid& grid, const GeoReference& geo);
// "a/b/ortho.tif" -> "a/b/ortho.tfw".
std::string WorldFilePath(const std::string& tiff_path);

// Reads a raster written by WriteGeoTiff (or any north-up GDAL raster): values,
// grid (local = global - geo_origin), type, nodata; *crs gets the CRS as WKT ("" if
// none). A world file next to the TIFF is used when the TIFF has no geotransform.
// Throws std::runtime_error naming the file when it cannot be read or is rotated.
Raster ReadGeoTiff(const std::string& path, const Eigen::Vector3d& geo_origin,
                   std::string* crs = nullptr);

}  // namespace facets
