#include "io/raster_io.h"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <system_error>

#include "io/atomic_file.h"

namespace facets {
namespace fs = std::filesystem;

void RasterGrid::Check() const {
  if (!(pixel_size > 0.0) || !std::isfinite(pixel_size)) {
    throw std::invalid_argument("RasterGrid: pixel_size must be positive and finite");
  }
  if (!std::isfinite(x0) || !std::isfinite(y0)) {
    throw std::invalid_argument("RasterGrid: x0, y0 must be finite");
  }
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("RasterGrid: width and height must be positive");
  }
}

RasterGrid RasterGrid::Covering(const Eigen::Vector2d& min, const Eigen::Vector2d& max,
                                double pixel_size) {
  if (!(pixel_size > 0.0) || !std::isfinite(pixel_size)) {
    throw std::invalid_argument("RasterGrid::Covering: pixel_size must be positive");
  }
  if (!min.allFinite() || !max.allFinite() || !(max.array() > min.array()).all()) {
    throw std::invalid_argument("RasterGrid::Covering: need finite min < max");
  }
  // The small tolerance keeps an extent that is already a multiple of the pixel size
  // (24 m at 0.24 m) from gaining a column through rounding noise.
  constexpr double kEps = 1e-9;
  RasterGrid grid;
  grid.pixel_size = pixel_size;
  const double col0 = std::floor(min.x() / pixel_size + kEps);
  const double col1 = std::ceil(max.x() / pixel_size - kEps);
  const double row0 = std::floor(min.y() / pixel_size + kEps);
  const double row1 = std::ceil(max.y() / pixel_size - kEps);
  grid.x0 = col0 * pixel_size;
  grid.y0 = row1 * pixel_size;
  grid.width = std::max(1, static_cast<int>(col1 - col0));
  grid.height = std::max(1, static_cast<int>(row1 - row0));
  return grid;
}

void Raster::Allocate(const RasterGrid& g, int num_bands, RasterType t, float fill) {
  g.Check();
  if (num_bands <= 0) throw std::invalid_argument("Raster: bands must be positive");
  grid = g;
  bands = num_bands;
  type = t;
  data.assign(static_cast<size_t>(g.NumPixels()) * num_bands, fill);
}

void RasterWriteOptions::Check() const {
  if (tile_size <= 0 || tile_size % 16 != 0) {
    throw std::invalid_argument("RasterWriteOptions: tile_size must be a positive multiple of 16");
  }
  static const std::array<const char*, 4> kKnown = {"DEFLATE", "LZW", "ZSTD", "NONE"};
  if (std::find(kKnown.begin(), kKnown.end(), compression) == kKnown.end()) {
    throw std::invalid_argument("RasterWriteOptions: unknown compression '" + compression +
                                "' (DEFLATE, LZW, ZSTD, NONE)");
  }
}

namespace {

void RegisterGdal() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

// Silences GDAL's stderr output for one scope; the last message is still kept for
// our own exceptions (CPLGetLastErrorMsg).
class QuietGdal {
 public:
  QuietGdal() {
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
  }
  ~QuietGdal() { CPLPopErrorHandler(); }
  QuietGdal(const QuietGdal&) = delete;
  QuietGdal& operator=(const QuietGdal&) = delete;
};

std::string GdalMessage() {
  const char* msg = CPLGetLastErrorMsg();
  return (msg && *msg) ? std::string(": ") + msg : std::string();
}

std::string Shortest(double value) {
  std::array<char, 64> buf;
  const auto result = std::to_chars(buf.data(), buf.data() + buf.size(), value);
  return std::string(buf.data(), result.ptr);
}

GDALDataType GdalType(RasterType type) {
  switch (type) {
    case RasterType::kUInt8:
      return GDT_Byte;
    case RasterType::kUInt16:
      return GDT_UInt16;
    case RasterType::kFloat32:
      return GDT_Float32;
  }
  return GDT_Float32;
}

void RemoveQuietly(const std::string& path) {
  std::error_code ignored;
  fs::remove(path, ignored);
}

void ValidateRaster(const std::string& path, const Raster& raster) {
  try {
    raster.grid.Check();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  if (raster.bands <= 0) throw std::invalid_argument(path + ": raster has no bands");
  if (raster.data.size() != static_cast<size_t>(raster.grid.NumPixels()) * raster.bands) {
    throw std::invalid_argument(path + ": raster data size " + std::to_string(raster.data.size()) +
                                " does not match width x height x bands");
  }
  if (raster.nodata) {
    const double nd = *raster.nodata;
    const bool ok =
        raster.type == RasterType::kFloat32 ||
        (raster.type == RasterType::kUInt8 && nd >= 0 && nd <= 255 && nd == std::floor(nd)) ||
        (raster.type == RasterType::kUInt16 && nd >= 0 && nd <= 65535 && nd == std::floor(nd));
    if (!ok) {
      throw std::invalid_argument(path + ": nodata value " + Shortest(nd) +
                                  " is not representable in the raster type");
    }
  }
}

// One band as the file's sample type, rounded and clamped for integer types.
template <typename T>
std::vector<T> ConvertBand(const Raster& raster, int band) {
  const size_t n = static_cast<size_t>(raster.grid.NumPixels());
  const float* src = raster.data.data() + band * n;
  std::vector<T> out(n);
  constexpr double kMax = std::numeric_limits<T>::max();
  for (size_t i = 0; i < n; ++i) {
    const double v = src[i];
    out[i] = std::isfinite(v) ? static_cast<T>(std::clamp(std::round(v), 0.0, kMax)) : T(0);
  }
  return out;
}

// GTiff creation options: tiles for rasters larger than one tile, the compression with
// its predictor (floating point or horizontal differencing), BigTIFF when needed, pixel
// interleaving for several bands and RGB photometric for 8/16-bit colour.
void SetCreateOptions(const Raster& raster, const RasterWriteOptions& options,
                      CPLStringList* create_options) {
  const RasterGrid& grid = raster.grid;
  const bool is_float = raster.type == RasterType::kFloat32;
  const int tile = options.tile_size;
  // Tiny rasters stay striped: a 256 x 256 tile for a 20 x 20 raster wastes space.
  if (grid.width > tile || grid.height > tile) {
    create_options->SetNameValue("TILED", "YES");
    create_options->SetNameValue("BLOCKXSIZE", std::to_string(tile).c_str());
    create_options->SetNameValue("BLOCKYSIZE", std::to_string(tile).c_str());
  }
  create_options->SetNameValue("COMPRESS", options.compression.c_str());
  if (options.compression != "NONE") {
    create_options->SetNameValue("PREDICTOR", is_float ? "3" : "2");
  }
  create_options->SetNameValue("BIGTIFF", "IF_SAFER");
  if (raster.bands > 1) create_options->SetNameValue("INTERLEAVE", "PIXEL");
  if (raster.bands == 3 && raster.type != RasterType::kFloat32) {
    create_options->SetNameValue("PHOTOMETRIC", "RGB");
  }
}

// Band b (0-based) of the raster in its own type.
CPLErr WriteBand(GDALRasterBand* band, const Raster& raster, int b) {
  const RasterGrid& grid = raster.grid;
  const size_t n = static_cast<size_t>(grid.NumPixels());
  switch (raster.type) {
    case RasterType::kUInt8: {
      std::vector<uint8_t> buf = ConvertBand<uint8_t>(raster, b);
      return band->RasterIO(GF_Write, 0, 0, grid.width, grid.height, buf.data(), grid.width,
                            grid.height, GDT_Byte, 0, 0);
    }
    case RasterType::kUInt16: {
      std::vector<uint16_t> buf = ConvertBand<uint16_t>(raster, b);
      return band->RasterIO(GF_Write, 0, 0, grid.width, grid.height, buf.data(), grid.width,
                            grid.height, GDT_UInt16, 0, 0);
    }
    case RasterType::kFloat32:
      return band->RasterIO(GF_Write, 0, 0, grid.width, grid.height,
                            const_cast<float*>(raster.data.data() + b * n), grid.width,
                            grid.height, GDT_Float32, 0, 0);
  }
  return CE_None;
}

// The geotransform and CRS (when the georeference has a CRS), nodata and every band;
// returns what failed, "" when all was written.
std::string WriteDatasetContents(GDALDataset* ds, const Raster& raster, const GeoReference& geo,
                                 OGRSpatialReference* srs) {
  const RasterGrid& grid = raster.grid;
  std::string error;
  if (!geo.crs.empty()) {
    double gt[6] = {geo.origin.x() + grid.x0, grid.pixel_size, 0.0, geo.origin.y() + grid.y0, 0.0,
                    -grid.pixel_size};
    if (ds->SetGeoTransform(gt) != CE_None) error = "cannot set the geotransform" + GdalMessage();
    if (error.empty() && ds->SetSpatialRef(srs) != CE_None) {
      error = "cannot set the CRS" + GdalMessage();
    }
  }
  for (int b = 0; b < raster.bands && error.empty(); ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b + 1);
    if (raster.nodata && band->SetNoDataValue(*raster.nodata) != CE_None) {
      error = "cannot set nodata" + GdalMessage();
      break;
    }
    if (WriteBand(band, raster, b) != CE_None) {
      error = "cannot write band " + std::to_string(b + 1) + GdalMessage();
    }
  }
  return error;
}

}  // namespace

std::string WorldFilePath(const std::string& tiff_path) {
  fs::path p(tiff_path);
  p.replace_extension(".tfw");
  return p.string();
}

std::string WorldFileText(const RasterGrid& grid, const GeoReference& geo) {
  // Line order of the ESRI world file: A (x size), D, B (rotations), E (-y size),
  // C, F = global coordinates of the CENTRE of the top-left pixel.
  const double cx = geo.origin.x() + grid.x0 + 0.5 * grid.pixel_size;
  const double cy = geo.origin.y() + grid.y0 - 0.5 * grid.pixel_size;
  std::string text;
  for (double v : {grid.pixel_size, 0.0, 0.0, -grid.pixel_size, cx, cy}) {
    text += Shortest(v);
    text += '\n';
  }
  return text;
}

void WriteGeoTiff(const std::string& path, const Raster& raster, const GeoReference& geo,
                  const RasterWriteOptions& options) {
  options.Check();
  ValidateRaster(path, raster);
  if (!geo.origin.allFinite())
    throw std::invalid_argument(path + ": georeference origin is not finite");
  RegisterGdal();
  QuietGdal quiet;

  OGRSpatialReference srs;
  if (!geo.crs.empty()) {
    if (srs.SetFromUserInput(geo.crs.c_str()) != OGRERR_NONE) {
      throw std::invalid_argument(path + ": unknown CRS '" + geo.crs + "'" + GdalMessage());
    }
    // Geotransforms are always easting/northing (x, y), whatever axis order the
    // authority defines for the CRS.
    srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  }

  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (!driver) throw std::runtime_error(path + ": GDAL has no GTiff driver");
  const RasterGrid& grid = raster.grid;
  CPLStringList create_options;
  SetCreateOptions(raster, options, &create_options);

  const std::string tmp = CreateTemporaryBeside(path);
  const std::string tmp_aux = tmp + ".aux.xml";
  GDALDataset* ds = driver->Create(tmp.c_str(), grid.width, grid.height, raster.bands,
                                   GdalType(raster.type), create_options.List());
  if (!ds) {
    RemoveQuietly(tmp);
    throw std::runtime_error(path + ": cannot create '" + tmp + "'" + GdalMessage());
  }
  std::string error = WriteDatasetContents(ds, raster, geo, &srs);
  // GDAL 3.6's GDALClose returns nothing: a failure while flushing (disk full) shows
  // only as a CE_Failure in the error state.
  CPLErrorReset();
  GDALClose(ds);
  if (error.empty() && CPLGetLastErrorType() >= CE_Failure) {
    error = "write failed" + GdalMessage();
  }
  if (!error.empty()) {
    RemoveQuietly(tmp);
    RemoveQuietly(tmp_aux);
    throw std::runtime_error(path + ": " + error);
  }

  if (geo.crs.empty()) WriteFileAtomically(WorldFilePath(path), WorldFileText(grid, geo));
  // A CRS GeoTIFF keys cannot hold goes to a side file (.aux.xml); keep it with the
  // TIFF, and never leave an old one that would override the new georeferencing.
  if (fs::exists(tmp_aux)) {
    CommitTemporary(tmp_aux, path + ".aux.xml");
  } else {
    RemoveQuietly(path + ".aux.xml");
  }
  CommitTemporary(tmp, path);
}

Raster ReadGeoTiff(const std::string& path, const Eigen::Vector3d& geo_origin, std::string* crs) {
  RegisterGdal();
  QuietGdal quiet;
  if (!fs::exists(path)) throw std::runtime_error(path + ": no such file");
  struct Closer {
    void operator()(GDALDataset* d) const { GDALClose(d); }
  };
  std::unique_ptr<GDALDataset, Closer> ds(
      GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!ds) throw std::runtime_error(path + ": cannot open as a raster" + GdalMessage());
  Raster raster;
  raster.bands = ds->GetRasterCount();
  if (raster.bands <= 0) throw std::runtime_error(path + ": no raster bands");
  raster.grid.width = ds->GetRasterXSize();
  raster.grid.height = ds->GetRasterYSize();
  double gt[6] = {0, 1, 0, 0, 0, 1};
  if (ds->GetGeoTransform(gt) != CE_None) {
    throw std::runtime_error(path + ": no georeferencing (neither geotransform nor world file)");
  }
  if (gt[2] != 0.0 || gt[4] != 0.0 || !(gt[1] > 0.0) || std::abs(gt[1] + gt[5]) > 1e-12 * gt[1]) {
    throw std::runtime_error(path + ": not a north-up raster with square pixels");
  }
  raster.grid.pixel_size = gt[1];
  raster.grid.x0 = gt[0] - geo_origin.x();
  raster.grid.y0 = gt[3] - geo_origin.y();
  GDALRasterBand* first = ds->GetRasterBand(1);
  switch (first->GetRasterDataType()) {
    case GDT_Byte:
      raster.type = RasterType::kUInt8;
      break;
    case GDT_UInt16:
      raster.type = RasterType::kUInt16;
      break;
    default:
      raster.type = RasterType::kFloat32;
      break;
  }
  int has_nodata = 0;
  const double nodata = first->GetNoDataValue(&has_nodata);
  if (has_nodata) raster.nodata = nodata;
  const size_t n = static_cast<size_t>(raster.grid.NumPixels());
  raster.data.resize(n * raster.bands);
  for (int b = 0; b < raster.bands; ++b) {
    if (ds->GetRasterBand(b + 1)->RasterIO(GF_Read, 0, 0, raster.grid.width, raster.grid.height,
                                           raster.data.data() + b * n, raster.grid.width,
                                           raster.grid.height, GDT_Float32, 0, 0) != CE_None) {
      throw std::runtime_error(path + ": cannot read band " + std::to_string(b + 1) +
                               GdalMessage());
    }
  }
  if (crs) {
    crs->clear();
    if (const OGRSpatialReference* srs = ds->GetSpatialRef()) {
      char* wkt = nullptr;
      if (srs->exportToWkt(&wkt) == OGRERR_NONE && wkt) *crs = wkt;
      CPLFree(wkt);
    }
  }
  return raster;
}

}  // namespace facets
