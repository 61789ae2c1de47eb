// The search along the normals between levels (engine/normal_search.h) on the seed gable
// roof (stereo pair, 0.24 m ground pixel): a TIN four pixels below the true roof and
// terrain must come back to within half a pixel, and a TIN on the truth must stay.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

#include "engine/level_images.h"
#include "engine/normal_search.h"
#include "engine/reconstruction.h"
#include "io/colmap_io.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"
#include "tests/truth_start.h"

namespace facets {
namespace {

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

class NormalSearchGable : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    scene_ = new Scene(LoadScene(std::string(FACETS_SOURCE_DIR) + "/scenes/data/seed_gable_parallel.json"));
    const std::string dir = testing::TempDir() + "/facets_normal_search_gable";
    RenderScene(*scene_, dir);
    block_ = new ImageBlock(ReadColmapModel(dir + "/sparse", dir + "/images"));
    loaded_ = new LoadedImages;
    LoadLevelImages(*block_, /*grey=*/true, loaded_);
    truth_ = new TruthMesh(BuildTruthMesh(*scene_));
    renderer_ = new Renderer(*scene_, *truth_);
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete truth_;
    delete loaded_;
    delete block_;
    delete scene_;
  }
  // Height errors of the interior vertices against the truth below / above them.
  static std::vector<double> HeightErrors(const TinMesh& mesh) {
    std::vector<double> errors;
    for (auto vh : mesh.vertices()) {
      if (mesh.is_boundary(vh)) continue;
      const auto p = mesh.point(vh);
      errors.push_back(std::abs(p[2] - TruthHeight(*renderer_, p[0], p[1])));
    }
    return errors;
  }
  // A grid with 1 m spacing (the level-0 edge of the seeds' 2-pixel facets is 1.9 m)
  // `shift` below the truth, normals set.
  static TinMesh Start(double shift) {
    TinMesh mesh = StartBelowTruth(*scene_, *renderer_, 1.0, shift);
    UpdateVertexNormals(&mesh);
    return mesh;
  }
  static Scene* scene_;
  static ImageBlock* block_;
  static LoadedImages* loaded_;
  static TruthMesh* truth_;
  static Renderer* renderer_;
};

// Every vertex searched (the default searches steep vertices only; the gable's roof is not).
NormalSearchOptions EveryVertex() {
  NormalSearchOptions options;
  options.min_angle_to_views_deg = 0.0;
  return options;
}
Scene* NormalSearchGable::scene_ = nullptr;
ImageBlock* NormalSearchGable::block_ = nullptr;
LoadedImages* NormalSearchGable::loaded_ = nullptr;
TruthMesh* NormalSearchGable::truth_ = nullptr;
Renderer* NormalSearchGable::renderer_ = nullptr;

TEST_F(NormalSearchGable, FourPixelsBelowComesBackWithinHalfAPixel) {
  const double gsd = scene_->ground_pixel_size;
  TinMesh mesh = Start(4.0 * gsd);
  const double before = Median(HeightErrors(mesh));
  const NormalSearchReport report = SearchAlongNormals(&mesh, loaded_->images, gsd, EveryVertex());
  const std::vector<double> errors = HeightErrors(mesh);
  const double after = Median(errors);
  const double within = std::count_if(errors.begin(), errors.end(), [&](double e) { return e < 0.5 * gsd; }) /
                        static_cast<double>(errors.size());
  std::cout << "searched " << report.searched << ", peaks " << report.peaks << ", moved " << report.moved
            << " (median " << report.median_move << " m), limited " << report.limited << "; height error median "
            << before << " -> " << after << " m, within half a pixel " << within << "\n";
  EXPECT_NEAR(before, 4.0 * gsd, 1e-6);
  EXPECT_GT(report.searched, static_cast<int>(0.9 * errors.size()));
  EXPECT_LT(after, 0.25 * gsd);
  EXPECT_GT(within, 0.75);  // 80 %: the rest found no clear peak and stay
}

TEST_F(NormalSearchGable, OnTheTruthNothingMovesFar) {
  const double gsd = scene_->ground_pixel_size;
  TinMesh mesh = Start(0.0);
  const NormalSearchReport report = SearchAlongNormals(&mesh, loaded_->images, gsd, EveryVertex());
  const std::vector<double> errors = HeightErrors(mesh);
  const double far = std::count_if(errors.begin(), errors.end(), [&](double e) { return e > gsd; }) /
                     static_cast<double>(errors.size());
  std::cout << "moved " << report.moved << " of " << report.searched << " (median " << report.median_move
            << " m); height error median " << Median(errors) << " m, beyond a pixel " << far << "\n";
  EXPECT_LT(report.moved, static_cast<int>(0.05 * report.searched));
  EXPECT_LT(far, 0.02);
}

// By default only vertices whose normal turns more than 45 degrees from their images
// are searched: a 20-degree roof seen from above is left to the adjustment.
TEST_F(NormalSearchGable, RoofsAreNotSearchedByDefault) {
  const double gsd = scene_->ground_pixel_size;
  TinMesh mesh = Start(4.0 * gsd);
  const NormalSearchReport report = SearchAlongNormals(&mesh, loaded_->images, gsd, NormalSearchOptions());
  EXPECT_EQ(report.searched, 0);
  EXPECT_EQ(report.moved, 0);
  EXPECT_NEAR(Median(HeightErrors(mesh)), 4.0 * gsd, 1e-6);
}

// Through the pipeline (`facets reconstruct --normal-search`): every level below the
// coarsest is searched and reported, and the roof still comes out right.
TEST_F(NormalSearchGable, ReconstructSearchesEveryFinerLevel) {
  ReconstructionOptions options;
  options.levels = 3;
  options.start = StartSurfaceKind::kPlane;  // at the tie points' median height, as the seed table
  options.normal_search = true;
  options.normal_search_options = EveryVertex();
  ImageBlock block = *block_;
  block.roi = scene_->roi;
  const Reconstruction r = Reconstruct(block, options);
  ASSERT_EQ(r.report.levels.size(), 3u);
  EXPECT_EQ(r.report.levels[0].normal_search.searched, 0);  // the coarsest: nothing to search yet
  for (size_t k = 1; k < 3; ++k) {
    const NormalSearchReport& ns = r.report.levels[k].normal_search;
    std::cout << "level " << r.report.levels[k].level << ": searched " << ns.searched << ", peaks " << ns.peaks
              << ", moved " << ns.moved << "\n";
    EXPECT_GT(ns.searched, static_cast<int>(0.5 * r.report.levels[k].vertices));
  }
  EXPECT_NE(r.report.Json().find("\"normal_search\""), std::string::npos);
  const double median = Median(HeightErrors(r.mesh));
  std::cout << "height error median " << median << " m, sigma0 " << r.report.levels.back().window.sigma0 << "\n";
  EXPECT_LT(median, 0.1 * scene_->ground_pixel_size);
}

}  // namespace
}  // namespace facets
