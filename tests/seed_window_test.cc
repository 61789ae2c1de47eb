// End-to-end: one window of the engine core on the seed gable-roof stereo pair
// (DESIGN.md section 7; issue 5 acceptance). Renders the bundled scene, starts from the
// true surface shifted down, adjusts on the finest level and compares with the truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>
#include <random>

#include <Eigen/Geometry>

#include "engine/solver/pcg.h"
#include "engine/images/level_images.h"
#include "engine/solver/window_adjustment.h"
#include "io/colmap_io.h"
#include "io/image_io.h"
#include "mesh/tin.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"
#include "tests/rendered_scene.h"
#include "tests/truth_start.h"

namespace facets {
namespace {

struct SeedResult {
  WindowReport report;
  CsrMatrix normal;        // normal equations of the last iteration
  Eigen::VectorXd rhs;
  double rms = 0.0;          // true height errors, interior vertices (m)
  double rms_surface = 0.0;  // true height errors of the G1 surface (tessellation nodes
                             // of faces away from the window border), m
  double mean_sigma = 0.0;   // mean reported sigma of dn, interior vertices (m)
  double rms_patch = 0.0, mean_sigma_patch = 0.0, mean_sigma_outside = 0.0;
  std::vector<Eigen::Vector3d> vertices;  // adjusted positions
};

struct SeedRun {
  std::string scene_file = "seed_gable_parallel.json";
  double noise = 4.0;
  double shift = 0.3;
  AdjustmentOptions options;
  // Non-empty: turn each grey image into one channel per gain (colour / multispectral
  // images: one grey value per channel and node, geometry shared).
  std::vector<double> channel_gains;
  // Constant-albedo patch (XY rectangle, min/max), to split the statistics.
  std::optional<Eigen::AlignedBox2d> patch;
  // > 0: instead of the renderer's white noise, add noise of this standard deviation
  // that is correlated between neighbouring pixels (white noise filtered with the 3x3
  // binomial kernel: correlation 2/3 at one pixel, 1/6 at two, along each axis).
  double correlated_noise = 0.0;
};

// Adds correlated Gaussian noise of standard deviation sigma to every channel.
void AddCorrelatedNoise(double sigma, unsigned seed, ImagePlanes* planes) {
  std::mt19937 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int w = planes->width, h = planes->height;
  // The separable [1 2 1] / 4 kernel keeps 6/16 of a white field's standard deviation.
  const double white = sigma * 16.0 / 6.0;
  for (int c = 0; c < planes->channels; ++c) {
    std::vector<double> n(static_cast<size_t>(w + 2) * (h + 2));
    for (double& v : n) v = white * normal(random);
    auto at = [&](int x, int y) { return n[static_cast<size_t>(y + 1) * (w + 2) + x + 1]; };
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        double sum = 0.0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) sum += (2 - std::abs(dx)) * (2 - std::abs(dy)) * at(x + dx, y + dy);
        planes->at(c, planes->x0 + x, planes->y0 + y) += static_cast<float>(sum / 16.0);
      }
    }
  }
}

SeedResult RunSeedWindow(const SeedRun& run) {
  const std::string scene_file = run.scene_file[0] == '/' ? run.scene_file : std::string(FACETS_SOURCE_DIR) + "/scenes/data/" + run.scene_file;
  const Scene scene = LoadScene(scene_file);
  // The render of this scene and noise, shared through the test binary's render cache.
  RenderOptions render_options;
  render_options.noise_sigma = run.correlated_noise > 0.0 ? 0.0 : run.noise;
  const std::string dir = RenderSceneOnce(scene_file, scene, render_options);

  const ImageBlock block = ReadColmapModel(dir + "/sparse", dir + "/images");
  LoadedImages loaded;
  LoadLevelImages(block, /*grey=*/true, &loaded);
  if (!run.channel_gains.empty()) {
    for (ImagePlanes& planes : loaded.planes) {
      ImagePlanes multi = planes;
      multi.channels = static_cast<int>(run.channel_gains.size());
      multi.data.clear();
      for (double gain : run.channel_gains)
        for (float g : planes.data) multi.data.push_back(static_cast<float>(gain * g));
      planes = std::move(multi);
    }
  }
  if (run.correlated_noise > 0.0) {
    for (size_t k = 0; k < loaded.planes.size(); ++k) AddCorrelatedNoise(run.correlated_noise, 17 + k, &loaded.planes[k]);
  }
  const std::vector<LevelImage>& images = loaded.images;

  const TruthMesh truth = BuildTruthMesh(scene);
  const Renderer renderer(scene, truth);
  auto truth_z = [&](double x, double y) { return TruthHeight(renderer, x, y); };
  // 4x4 grey facets of 0.5 m = about 2x2 pixels (seed 000).
  TinMesh mesh = StartBelowTruth(scene, renderer, 2.0, run.shift);

  WindowAdjustment adjustment(&mesh, images, run.options);
  SeedResult result;
  result.report = adjustment.Run();
  result.normal = adjustment.normal_equations();
  result.rhs = adjustment.right_hand_side();
  for (auto vh : mesh.vertices()) result.vertices.push_back(ToEigen(mesh.point(vh)));

  // Constant-grey patch of the scene, if any (albedo patches in XY).
  double sum2 = 0, sum_sigma = 0, patch2 = 0, patch_sigma = 0, outside_sigma = 0;
  int count = 0, patch_count = 0, outside_count = 0;
  for (auto vh : mesh.vertices()) {
    if (mesh.is_boundary(vh)) continue;
    const Eigen::Vector3d x = ToEigen(mesh.point(vh));
    const double dz = x.z() - truth_z(x.x(), x.y());
    sum2 += dz * dz;
    if (run.patch) {
      // Inside: all adjacent faces on the patch; around: a 1-4 m ring outside it.
      Eigen::AlignedBox2d inner(run.patch->min().array() + 1.0, run.patch->max().array() - 1.0);
      const double outside = run.patch->exteriorDistance(x.head<2>());
      if (inner.contains(x.head<2>())) {
        patch2 += dz * dz;
        patch_sigma += result.report.vertex_sigma[vh.idx()];
        ++patch_count;
      } else if (outside > 1.0 && outside < 4.0) {
        outside_sigma += result.report.vertex_sigma[vh.idx()];
        ++outside_count;
      }
    }
    sum_sigma += result.report.vertex_sigma[vh.idx()];
    ++count;
  }
  result.rms = std::sqrt(sum2 / count);
  if (run.patch) {
    result.rms_patch = std::sqrt(patch2 / patch_count);
    result.mean_sigma_patch = patch_sigma / patch_count;
    result.mean_sigma_outside = outside_sigma / outside_count;
    std::cout << "  constant patch: " << patch_count << " vertices, rms(dZ) " << result.rms_patch
              << " m, mean sigma " << result.mean_sigma_patch << " m; 1-4 m around it: mean sigma "
              << result.mean_sigma_outside << " m\n";
  }
  {
    // The surface itself: tessellation nodes of faces none of whose vertices lies on
    // the window border (the G1 surface is what the user gets, not only the vertices).
    const Tessellation& tess = adjustment.tessellation();
    std::vector<bool> inner_face(mesh.n_faces(), true);
    for (auto fh : mesh.faces())
      for (auto vh : mesh.fv_range(fh))
        if (mesh.is_boundary(vh)) inner_face[fh.idx()] = false;
    double s2 = 0;
    int n = 0;
    for (size_t p = 0; p < tess.points.size(); ++p) {
      if (!inner_face[tess.point_face[p]]) continue;
      const double dz = tess.points[p].z() - truth_z(tess.points[p].x(), tess.points[p].y());
      s2 += dz * dz;
      ++n;
    }
    result.rms_surface = std::sqrt(s2 / n);
  }
  result.mean_sigma = sum_sigma / count;
  std::cout << scene.name << " noise " << run.noise << ": " << result.report.BriefReport()
            << "\n  rms(dZ) " << result.rms << " m (surface " << result.rms_surface << " m), mean sigma " << result.mean_sigma
            << " m, ratio " << result.rms / result.mean_sigma << "\n";
  for (const auto& it : result.report.iterations) {
    std::cout << "  it " << it.iteration << " obs " << it.observations << " cg " << it.cg_iterations
              << " sigma0 " << it.sigma0 << " max dn " << it.max_dn_interior << "/"
              << it.max_dn_border << "/" << it.max_dn_corner << " cast " << it.seconds_cast
              << " s, linearise " << it.seconds_linearise << " s, solve " << it.seconds_solve
              << " s, update " << it.seconds_update << " s\n";
  }
  return result;
}

// Issue 5 acceptance: finest level, one window, start 0.3 m below the truth, noise 4.
TEST(SeedWindow, GableRoofWithNoise) {
  SeedRun run;
  run.options.break_off = 0.005;
  const SeedResult r = RunSeedWindow(run);
  EXPECT_TRUE(r.report.converged);
  EXPECT_NEAR(r.report.sigma0, 4.0, 0.4);
  EXPECT_LE(r.rms, 0.06);
  EXPECT_GT(r.rms / r.mean_sigma, 0.5);
  EXPECT_LT(r.rms / r.mean_sigma, 2.0);
  // White noise: the residuals of neighbouring pixels are uncorrelated, the variance
  // factor for correlated residuals stays near 1.
  EXPECT_LT(r.report.variance_factor, 1.2);
}

// Noise correlated between neighbouring pixels (like low-passed or resampled images):
// sigma from the diagonal of N^-1 alone is too optimistic; the variance factor from the
// residuals' correlation (AdjustmentOptions::correlated_residuals) brings the reported
// sigma closer to the true errors.
TEST(SeedWindow, CorrelatedNoiseVarianceFactor) {
  SeedRun run;
  run.correlated_noise = 4.0;
  run.options.break_off = 0.005;
  run.options.correlated_residuals = false;
  const SeedResult white = RunSeedWindow(run);
  run.options.correlated_residuals = true;
  const SeedResult correlated = RunSeedWindow(run);
  std::cout << "correlated noise 4: lag-1 residual correlation " << correlated.report.residual_rho_x << " / "
            << correlated.report.residual_rho_y << ", variance factor " << correlated.report.variance_factor
            << "; rms / mean sigma without the factor " << white.rms / white.mean_sigma << ", with it "
            << correlated.rms / correlated.mean_sigma << "\n";
  EXPECT_GT(correlated.report.residual_rho_x, 0.4);
  EXPECT_GT(correlated.report.variance_factor, 1.5);
  EXPECT_EQ(white.report.variance_factor, 1.0);
  EXPECT_NEAR(correlated.rms, white.rms, 1e-12);  // same surface, only sigma differs
  // Measured: factor 4.26, ratio 3.58 without and 1.73 with it (white noise: 1.13). The
  // grey values absorb the smooth part of the noise, so the residuals show less of its
  // correlation (lag 1: 0.56 / 0.46 instead of 2/3) and the factor corrects only part.
  EXPECT_GT(correlated.rms / correlated.mean_sigma, 0.5);
  EXPECT_LT(correlated.rms / correlated.mean_sigma, 2.0);
  EXPECT_GT(white.rms / white.mean_sigma, 1.5 * correlated.rms / correlated.mean_sigma);
}

TEST(SeedWindow, GableRoofWithoutNoise) {
  SeedRun run;
  run.noise = 0.0;
  run.options.break_off = 0.001;
  const SeedResult r = RunSeedWindow(run);
  EXPECT_TRUE(r.report.converged);
  EXPECT_LE(r.rms, 0.015);
}

// Three channels with different gains: one grey value per channel, geometry shared.
TEST(SeedWindow, MultiChannelImagesShareTheGeometry) {
  SeedRun run;
  run.channel_gains = {1.0, 0.8, 0.6};
  run.options.break_off = 0.005;
  const SeedResult r = RunSeedWindow(run);
  EXPECT_TRUE(r.report.converged);
  EXPECT_LE(r.rms, 0.06);
  EXPECT_GT(r.report.sigma0, 2.0);  // noise 4 scaled by gains 0.6-1.0
  EXPECT_LT(r.report.sigma0, 4.4);
}

// Solvers on real normal equations of a window: SSOR-PCG agrees with the sparse
// direct solution and needs at most half the iterations of Jacobi-PCG.
TEST(SeedWindow, SsorPcgOnRealNormalEquations) {
  SeedRun run;
  run.options.max_iterations = 2;
  const SeedResult r = RunSeedWindow(run);
  const Eigen::VectorXd direct = SolveDirect(r.normal, r.rhs);
  PcgOptions ssor;
  ssor.relative_tolerance = 1e-12;
  ssor.max_iterations = 20000;
  PcgOptions jacobi = ssor;
  jacobi.preconditioner = Preconditioner::kJacobi;
  Eigen::VectorXd x_ssor, x_jacobi;
  const PcgSummary s = SolvePcg(r.normal, r.rhs, ssor, &x_ssor);
  const PcgSummary j = SolvePcg(r.normal, r.rhs, jacobi, &x_jacobi);
  const double err_ssor = (x_ssor - direct).norm() / direct.norm();
  const double err_jacobi = (x_jacobi - direct).norm() / direct.norm();
  std::cout << "window normal equations: " << r.normal.rows() << " unknowns, "
            << r.normal.nonZeros() << " non-zeros; SSOR-PCG " << s.iterations
            << " iterations (rel. error " << err_ssor << "), Jacobi-PCG " << j.iterations
            << " iterations (rel. error " << err_jacobi << ")\n";
  EXPECT_LT(err_ssor, 1e-8);
  EXPECT_LE(2 * s.iterations, j.iterations);
}

// The window solvers (AdjustmentOptions::solver): sparse LDL^T (default) and SSOR-PCG
// give the same adjusted window: vertex differences far below the vertices' sigma.
TEST(SeedWindow, LdltAndPcgGiveTheSameWindow) {
  SeedRun run;
  run.options.break_off = 0.005;
  run.options.solver = WindowSolver::kLdlt;
  const SeedResult ldlt = RunSeedWindow(run);
  run.options.solver = WindowSolver::kPcg;
  const SeedResult pcg = RunSeedWindow(run);
  ASSERT_EQ(ldlt.vertices.size(), pcg.vertices.size());
  EXPECT_EQ(ldlt.report.iterations.size(), pcg.report.iterations.size());
  EXPECT_EQ(ldlt.report.cg_iterations_total, 0);
  double worst = 0.0, worst_sigma = 0.0;
  for (size_t v = 0; v < ldlt.vertices.size(); ++v) {
    const double sigma = ldlt.report.vertex_sigma[v];
    if (sigma <= 0.0) continue;
    worst = std::max(worst, (ldlt.vertices[v] - pcg.vertices[v]).norm() / sigma);
    worst_sigma = std::max(worst_sigma, std::abs(sigma - pcg.report.vertex_sigma[v]) / sigma);
  }
  std::cout << "LDL^T vs SSOR-PCG: worst vertex difference " << worst << " sigma, worst sigma difference "
            << worst_sigma << " (relative); sigma0 " << ldlt.report.sigma0 << " vs " << pcg.report.sigma0 << "\n";
  EXPECT_LT(worst, 1e-3);
  // The two runs stop at surfaces up to 1.6e-4 sigma apart and each computes its sigma
  // where it stopped, so the sigmas need not agree closer than the surfaces do (4.1e-6
  // relative on a 2-core AMD EPYC with AVX2, session 21, where the bound of 1e-6 failed).
  EXPECT_LT(worst_sigma, 1e-4);
  EXPECT_NEAR(ldlt.report.sigma0, pcg.report.sigma0, 1e-6 * pcg.report.sigma0);
}

// Adaptive regularisation (seed 003) on the same pair: the same accuracy class.
TEST(SeedWindow, AdaptiveRegularisation) {
  SeedRun run;
  run.options.regularisation = Regularisation::kAdaptive;
  run.options.break_off = 0.005;
  const SeedResult r = RunSeedWindow(run);
  EXPECT_TRUE(r.report.converged);
  EXPECT_NEAR(r.report.sigma0, 4.0, 0.4);
  EXPECT_LE(r.rms, 0.06);
}

// Regularisation bridges the 8 m x 6 m constant-grey patch: no divergence, bounded
// errors, and the reported standard deviations there are visibly higher. A lower
// lambda than the default makes the contrast in precision visible (at 1500 the prior
// dominates the precision everywhere). Not asserted: convergence — the run ends in a
// limit cycle of about 1 cm at the patch (noted on issue 5).
TEST(SeedWindow, ConstantPatchIsBridged) {
  SeedRun run;
  run.scene_file = "seed_gable_parallel_patch.json";
  run.options.lambda = 500;
  run.options.break_off = 0.005;
  run.patch = Eigen::AlignedBox2d(Eigen::Vector2d(-2.0, -8.0), Eigen::Vector2d(6.0, -2.0));
  const SeedResult r = RunSeedWindow(run);
  EXPECT_NEAR(r.report.sigma0, 4.0, 0.5);
  EXPECT_LE(r.rms_patch, 0.15);
  EXPECT_LE(r.rms, 0.06);
  EXPECT_GT(r.mean_sigma_patch, 1.3 * r.mean_sigma_outside);
}

}  // namespace
}  // namespace facets
