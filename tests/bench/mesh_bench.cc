// Benchmark for mesh/: G1 interpolant evaluations per second per core, and the time to
// tessellate a ~100k-triangle mesh (1 and 2 TBB threads). Never run by CTest.
//   facets_mesh_bench
#include <tbb/global_control.h>

#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <vector>

#include "mesh/g1_patch.h"
#include "mesh/tessellation.h"
#include "mesh/tin.h"

namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main() {
  using facets::TinMesh;
  // Curved height field, 224 x 224 cells = 100,352 triangles.
  facets::StartGridOptions opt;
  opt.min = Eigen::Vector2d(0, 0);
  opt.max = Eigen::Vector2d(224, 224);
  opt.spacing = 1.0;
  opt.height = [](double x, double y) { return 5 * std::sin(0.05 * x) * std::cos(0.07 * y); };
  const TinMesh mesh = facets::MakeStartGrid(opt);
  std::printf("mesh: %zu vertices, %zu faces\n", mesh.n_vertices(), mesh.n_faces());

  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const std::vector<facets::G1Patch> patches = facets::BuildPatches(mesh);
    // Single thread: evaluate 10 interior points per face over all faces, repeated.
    const double bary[10][2] = {{0.1, 0.1}, {0.2, 0.3}, {0.33, 0.33}, {0.6, 0.2}, {0.1, 0.7},
                                {0.45, 0.45}, {0.05, 0.5}, {0.25, 0.05}, {0.7, 0.1}, {0.4, 0.2}};
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    size_t evals = 0;
    auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    for (int rep = 0; rep < 3; ++rep) {
      for (const auto& p : patches) {
        for (const auto& b : bary) sum += p.Evaluate(b[0], b[1]);
        evals += 10;
      }
    }
    double t = Seconds(t0);
    const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
    // CPU time as well: on a loaded machine wall time includes time slices of others.
    std::printf("Evaluate (point): %.2f M evaluations/s/core wall, %.2f M/s per CPU second "
                "(%zu in %.3f s, checksum %.3f)\n",
                evals / t * 1e-6, evals / cpu * 1e-6, evals, t, sum.sum());
    evals = 0;
    t0 = std::chrono::steady_clock::now();
    for (const auto& p : patches) {
      for (const auto& b : bary) sum += p.EvaluateWithDerivatives(b[0], b[1]).normal;
      evals += 10;
    }
    t = Seconds(t0);
    std::printf("EvaluateWithDerivatives (point+tangents+normal): %.2f M evaluations/s/core\n",
                evals / t * 1e-6);
  }
  for (int threads : {1, 2}) {
    tbb::global_control ctl(tbb::global_control::max_allowed_parallelism, threads);
    double best = 1e9, best_update = 1e9;
    facets::Tessellation tess;
    for (int rep = 0; rep < 3; ++rep) {
      auto t0 = std::chrono::steady_clock::now();
      tess = facets::Tessellate(mesh);
      best = std::min(best, Seconds(t0));
      t0 = std::chrono::steady_clock::now();
      facets::UpdateTessellationPoints(mesh, &tess);
      best_update = std::min(best_update, Seconds(t0));
    }
    std::printf("threads=%d: Tessellate %zu faces -> %zu nodes, %zu sub-triangles: %.3f s; "
                "UpdateTessellationPoints: %.3f s\n",
                threads, mesh.n_faces(), tess.points.size(), tess.triangles.size(), best,
                best_update);
  }
  return 0;
}
