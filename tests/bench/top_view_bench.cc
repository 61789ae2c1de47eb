// Benchmark of the top view (visibility/top_view.h) and the GeoTIFF writer: a 200 m x
// 200 m terrain with 64 box buildings, rasters at a chosen ground pixel size.
//   top_view_bench [pixel_size_m=0.1] [out_dir=/tmp]
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <string>

#include "io/raster_io.h"
#include "visibility/surface_scene.h"
#include "visibility/test_util.h"
#include "visibility/top_view.h"

int main(int argc, char** argv) {
  using namespace facets;
  using Clock = std::chrono::steady_clock;
  const double pixel = argc > 1 ? std::atof(argv[1]) : 0.1;
  const std::string out_dir = argc > 2 ? argv[2] : "/tmp";
  FlatMesh mesh;
  AppendGridForTesting(-100, -100, 100, 100, 100, 100,
                       [](double x, double y) { return 0.5 * std::sin(x / 20) * std::cos(y / 30); },
                       &mesh);
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) {
      const double x = -90 + 23.0 * i, y = -90 + 23.0 * j;
      AppendBoxForTesting({x, y, -1.0}, {x + 12, y + 9, 4.0 + (i + j) % 5}, false, &mesh);
    }
  }
  const Tessellation tess = TessellateFlatForTesting(mesh);
  std::vector<double> grey(tess.points.size());
  for (size_t k = 0; k < grey.size(); ++k) grey[k] = 128 + 60 * std::sin(tess.points[k].x());
  SurfaceScene scene(tess, /*refittable=*/false);
  const RasterGrid grid = RasterGrid::Covering({-100, -100}, {100, 100}, pixel);

  auto t0 = Clock::now();
  const TopView top = CastTopView(scene, tess, grid);
  auto t1 = Clock::now();
  const Raster ortho = MakeOrthophoto(top, tess, grey);
  const Raster dsm = MakeDsm(top);
  auto t2 = Clock::now();
  GeoReference geo;
  geo.crs = "EPSG:25832";
  geo.origin = {500000, 5700000, 0};
  WriteGeoTiff(out_dir + "/bench_ortho.tif", ortho, geo);
  WriteGeoTiff(out_dir + "/bench_dsm.tif", dsm, geo);
  auto t3 = Clock::now();
  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  std::cout << "facets " << tess.triangles.size() << ", grid " << grid.width << " x "
            << grid.height << " (" << grid.NumPixels() / 1e6 << " Mpx), hits " << top.stats.hits
            << "\ncast " << ms(t0, t1) << " ms (" << grid.NumPixels() / ms(t0, t1) / 1e3
            << " Mrays/s), ortho+dsm " << ms(t1, t2) << " ms, write 2 GeoTIFFs " << ms(t2, t3)
            << " ms\n";
  return 0;
}
