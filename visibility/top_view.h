// The top view of the 3D surface: one vertical ray per raster pixel, cast downward
// from above the surface, first hit only (DESIGN.md section 1, "true orthophoto and a
// DSM"). From it: the DSM (height of the hit), the true orthophoto (object grey values
// interpolated on the grey facet that was hit) and a sigma raster (any per-node value,
// interpolated the same way).
//
// "Highest surface wins" is exactly what a first hit from above gives: a roof edge
// occludes the ground below it, walls are parallel to the rays and are never hit
// except at grazing incidence, so facades do not smear into the orthophoto, and under
// an overhang the DSM holds the overhang's top, not the ground.
//
// Back faces: a first hit on a facet whose normal points down happens only where the
// reconstructed surface is open or folded (e.g. a balcony of which the images saw only
// the underside). By default that hit counts like any other (TopViewOptions::
// skip_back_faces = false): it is still the highest surface there, so the DSM keeps
// its height, and looking through it would show ground that cannot be seen from
// above. skip_back_faces = true continues the ray below every back face instead.
//
// Frames: grid and heights are local object coordinates (relative to the block
// origin); rasters are written with io/raster_io.h (global = origin + local).
#pragma once

#include <cstdint>
#include <vector>

#include "io/raster_io.h"
#include "mesh/tessellation.h"
#include "visibility/surface_scene.h"

namespace facets {

struct TopViewOptions {
  bool skip_back_faces = false;  // see the file comment
  // The rays start this far (object units, m) above the highest tessellation point:
  // far enough to clear the float rounding of Embree's ray origin, close enough that
  // the ray's float parameter stays fine.
  double start_margin = 1.0;

  // Throws std::invalid_argument on a value out of range.
  void Check() const;
};

struct TopViewStats {
  long long pixels = 0;
  long long hits = 0;
  long long misses = 0;      // nothing below the pixel centre
  long long back_faces = 0;  // first hits on a downward-facing facet (counted, see above)
};

// Per pixel (row-major, index row * width + col) the first hit from above.
struct TopView {
  RasterGrid grid;
  std::vector<int32_t> facet;  // sub-triangle s (Embree primitive id), -1 = no hit
  // Grey-facet barycentrics: the hit is (1-u-v) P0 + u P1 + v P2 on
  // Tessellation::triangles[facet]. Recomputed in double from the pixel centre's XY.
  std::vector<float> u, v;
  std::vector<double> z;  // local height of the hit; NaN where there is no hit
  TopViewStats stats;

  size_t Index(int col, int row) const {
    return static_cast<size_t>(row) * grid.width + col;
  }
  bool Hit(int col, int row) const { return facet[Index(col, row)] >= 0; }
};

// Casts the grid's pixel centres vertically downward into `scene`, which must be the
// SurfaceScene of `tessellation` (same facets in the same order; throws
// std::invalid_argument otherwise). Packets of 16 rays (rtcIntersect16), rows spread
// over threads (TBB); the result does not depend on the thread count.
TopView CastTopView(const SurfaceScene& scene, const Tessellation& tessellation,
                    const RasterGrid& grid, const TopViewOptions& options = {});

// DSM NoData: -9999 rather than NaN, because every GIS reads -9999 as a declared nodata
// value while NaN handling differs between tools; the value is stored in the file.
constexpr float kDsmNoData = -9999.0f;

// DSM: one float32 band of local heights (add GeoReference::origin.z() for global
// heights; the writer does not touch values), nodata where no surface lies below.
Raster MakeDsm(const TopView& top, float nodata = kDsmNoData);

// Per-node values (node-major: values[node * channels + c], one entry per
// Tessellation point) interpolated linearly on the hit grey facet with (1-u-v, u, v):
// one band per channel. Pixels without a hit, and pixels where a corner value is not
// finite (e.g. an undetermined node), get `nodata`. For integer types a valid value
// that would round to `nodata` is moved one step away from it, so that no surface
// pixel reads as a hole. Throws std::invalid_argument on a size mismatch.
Raster InterpolateNodeValues(const TopView& top, const Tessellation& tessellation,
                             const std::vector<double>& values, int channels,
                             RasterType type, float nodata);

// True orthophoto from the object grey values (node-major, `channels` per node), 8-bit
// by default; nodata 0 (a black grey value 0 on the surface becomes 1).
Raster MakeOrthophoto(const TopView& top, const Tessellation& tessellation,
                      const std::vector<double>& grey_values, int channels = 1,
                      RasterType type = RasterType::kUInt8, float nodata = 0.0f);

// Sigma raster (float32) from one standard deviation per node (object units for a
// height sigma; NaN for undetermined nodes -> nodata).
Raster MakeSigmaRaster(const TopView& top, const Tessellation& tessellation,
                       const std::vector<double>& node_sigma, float nodata = kDsmNoData);

}  // namespace facets
