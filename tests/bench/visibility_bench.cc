// Benchmark of the per-pixel first-hit query (visibility/pixel_cast.h) against bare
// Embree on the same scene and the same rays.
//
//   visibility_bench [repetitions]
//
// Scene: a 120 m x 120 m terrain (60 x 60 quads, smooth relief) with 40 box
// buildings, tessellated 4x4 per face (~120k sub-triangles); one 1000 x 750 pinhole
// camera looking obliquely at it. Both variants cast one ray per pixel in the same
// 32 x 32 tiles over TBB and the same 4x4 packets through rtcIntersect16, with the
// same ray generation (PixelRays::Direction) included in both timings:
//   bare: rtcIntersect16 and a hit count, nothing else;
//   full: CastPixels (hit + back-face and incidence test + facet -> face barycentric
//         mapping + compacted PixelObservation output).
// Each figure is the best of `repetitions` runs (default 7), at 1 and 2 threads.
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>

#include "visibility/pixel_cast.h"
#include "visibility/surface_scene.h"
#include "visibility/test_util.h"

namespace facets {
namespace {

Rigid3d LookAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d world_from_cam;
  world_from_cam << x, y, z;
  const Eigen::Matrix3d cam_from_world = world_from_cam.transpose();
  return Rigid3d(Eigen::Quaterniond(cam_from_world), -(cam_from_world * centre));
}

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

long long BareCast(const SurfaceScene& scene, const Camera& camera, const Rigid3d& pose,
                   int tile_size) {
  const PixelRays rays(camera, pose);
  const int tiles_x = (camera.width + tile_size - 1) / tile_size;
  const int tiles_y = (camera.height + tile_size - 1) / tile_size;
  tbb::combinable<long long> hits([] { return 0LL; });
  const RTCScene rtc_scene = scene.get();
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles_x * tiles_y, 1), [&](const auto& r) {
    long long& local_hits = hits.local();
    for (int t = r.begin(); t < r.end(); ++t) {
      const int tx0 = (t % tiles_x) * tile_size, ty0 = (t / tiles_x) * tile_size;
      const int tx1 = std::min(camera.width, tx0 + tile_size);
      const int ty1 = std::min(camera.height, ty0 + tile_size);
      for (int by = ty0; by < ty1; by += 4) {
        for (int bx = tx0; bx < tx1; bx += 4) {
          alignas(64) RTCRayHit16 packet;
          alignas(64) int valid[16];
          int n = 0;
          for (int y = by; y < by + 4; ++y) {
            for (int x = bx; x < bx + 4; ++x, ++n) {
              const bool inside = x < tx1 && y < ty1;
              valid[n] = inside ? -1 : 0;
              const Eigen::Vector3d d =
                  inside ? rays.Direction(x, y) : Eigen::Vector3d(0, 0, 1);
              SetPacketRay(&packet, n, rays.origin(), d);
            }
          }
          IntersectCoherent16(valid, rtc_scene, &packet);
          for (int i = 0; i < 16; ++i) {
            local_hits += valid[i] && packet.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
          }
        }
      }
    }
  });
  return hits.combine([](long long a, long long b) { return a + b; });
}

int Run(int repetitions) {
  FlatMesh mesh;
  AppendGridForTesting(-60, -60, 60, 60, 60, 60,
                       [](double x, double y) {
                         return 3.0 * std::sin(0.05 * x) * std::cos(0.04 * y) + 0.02 * x;
                       },
                       &mesh);
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> pos(-50, 50), size(4, 12), height(5, 25);
  for (int b = 0; b < 40; ++b) {
    const Eigen::Vector3d lo(pos(rng), pos(rng), -3.0);
    AppendBoxForTesting(lo, lo + Eigen::Vector3d(size(rng), size(rng), height(rng)),
                        /*with_bottom=*/false, &mesh);
  }
  Tessellation tess = TessellateFlatForTesting(mesh);
  const Camera camera =
      Camera::Create(CameraModel::kPinhole, 900, 900, 500, 375, 1000, 750);
  const Rigid3d pose = LookAt({0, -60, 70}, {0, 5, 0});
  const long long num_rays = static_cast<long long>(camera.width) * camera.height;
  const CastOptions options;  // defaults: valid observations only
  std::printf("native rtcIntersect16: %s\n",
              rtcGetDeviceProperty(EmbreeDevice::Shared().get(),
                                   RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)
                  ? "yes"
                  : "no");

  for (const bool refittable : {false, true}) {
    auto start = std::chrono::steady_clock::now();
    SurfaceScene scene(tess, refittable);
    const double build_seconds = Seconds(start);
    std::printf(
        "\n%s scene: %d faces, %d sub-triangles, %d points, built in %.1f ms; camera "
        "%dx%d (%lld rays)\n",
        refittable ? "refittable (dynamic, two-level BVH)" : "static (single-level BVH)",
        scene.NumFaces(), scene.NumFacets(), scene.NumPoints(), 1e3 * build_seconds,
        camera.width, camera.height, num_rays);
    for (int threads : {1, 2}) {
      tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);
      double bare_best = 1e30, full_best = 1e30;
      long long bare_hits = 0;
      CastStats stats;
      for (int r = 0; r < repetitions; ++r) {
        start = std::chrono::steady_clock::now();
        bare_hits = BareCast(scene, camera, pose, options.tile_size);
        bare_best = std::min(bare_best, Seconds(start));
        start = std::chrono::steady_clock::now();
        const CastResult result =
            CastPixels(scene, camera, pose, PixelRect::Full(camera), options);
        full_best = std::min(full_best, Seconds(start));
        stats = result.stats;
      }
      const double bare_rate = num_rays / bare_best, full_rate = num_rays / full_best;
      std::printf(
          "threads %d: bare %.2f ms = %.2f Mrays/s (%.2f per core, %lld hits); full %.2f ms "
          "= %.2f Mrays/s (%.2f per core, %lld observations, %lld misses, %lld back faces, "
          "%lld grazing); full/bare = %.1f%%\n",
          threads, 1e3 * bare_best, 1e-6 * bare_rate, 1e-6 * bare_rate / threads, bare_hits,
          1e3 * full_best, 1e-6 * full_rate, 1e-6 * full_rate / threads, stats.observations,
          stats.misses, stats.back_faces, stats.grazing, 100.0 * full_rate / bare_rate);
    }
    // Same topology, all vertices moved 1 cm along +z (2 threads): update in place
    // (refit where the scene allows it) and the full query on the updated tree.
    tbb::global_control two_threads(tbb::global_control::max_allowed_parallelism, 2);
    Tessellation moved = tess;
    double update_best = 1e30, cast_best = 1e30;
    for (int r = 0; r < repetitions; ++r) {
      for (Eigen::Vector3d& p : moved.points) p.z() += 0.01;
      start = std::chrono::steady_clock::now();
      scene.Update(moved);
      update_best = std::min(update_best, Seconds(start));
    }
    for (int r = 0; r < repetitions; ++r) {
      start = std::chrono::steady_clock::now();
      const CastResult result = CastPixels(scene, camera, pose, PixelRect::Full(camera), options);
      cast_best = std::min(cast_best, Seconds(start));
    }
    std::printf("update in place %.2f ms; full query after %d updates %.2f ms = %.2f Mrays/s "
                "(2 threads)\n",
                1e3 * update_best, repetitions, 1e3 * cast_best, 1e-6 * num_rays / cast_best);
  }
  return 0;
}

}  // namespace
}  // namespace facets

int main(int argc, char** argv) {
  const int repetitions = argc > 1 ? std::atoi(argv[1]) : 7;
  return facets::Run(std::max(1, repetitions));
}
