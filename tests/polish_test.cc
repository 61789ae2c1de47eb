// The polish (ReconstructionOptions::polish_robust_k): the finest level adjusted once more
// with robust weights. On the seed gable roof one image gets a white square over the roof
// (a specular flash, a car that drove off): plain least squares bends the roof under it,
// the robust polish rejects those pixels and puts the roof back.
#include <gtest/gtest.h>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include "engine/pipeline/reconstruction.h"
#include "io/colmap_io.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"
#include "tests/truth_start.h"

namespace facets {
namespace {

constexpr double kSquarePixels = 6.0;  // side of the white square in the image (1.4 m)

class PolishGable : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    scene_ = new Scene(LoadScene(std::string(FACETS_SOURCE_DIR) + "/scenes/data/seed_gable_parallel.json"));
    const std::string dir = testing::TempDir() + "/facets_polish_gable";
    RenderScene(*scene_, dir);
    block_ = new ImageBlock(ReadColmapModel(dir + "/sparse", dir + "/images"));
    block_->roi = scene_->roi;
    truth_ = new TruthMesh(BuildTruthMesh(*scene_));
    renderer_ = new Renderer(*scene_, *truth_);
    // The square: on the southern roof plane, 4 m from the ridge (y = 0), in the first image.
    spot_ = Eigen::Vector3d(3.0, -4.0, TruthHeight(*renderer_, 3.0, -4.0));
    const BlockImage& image = block_->images.front();
    const Eigen::Vector2d pixel = block_->CameraOf(image).ImageFromCam(image.cam_from_world * spot_);
    OIIO::ImageBuf buf(image.path);
    ASSERT_TRUE(buf.read(0, 0, true)) << buf.geterror();
    const int x0 = static_cast<int>(pixel.x() - 0.5 * kSquarePixels);
    const int y0 = static_cast<int>(pixel.y() - 0.5 * kSquarePixels);
    const std::vector<float> white(buf.nchannels(), 1.0f);
    ASSERT_TRUE(OIIO::ImageBufAlgo::fill(
        buf, white, OIIO::ROI(x0, x0 + static_cast<int>(kSquarePixels), y0, y0 + static_cast<int>(kSquarePixels))));
    ASSERT_TRUE(buf.write(image.path)) << buf.geterror();
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete truth_;
    delete block_;
    delete scene_;
  }
  // Largest height error of the vertices within `radius` (horizontal) of the spot.
  static double WorstNearSpot(const TinMesh& mesh, double radius) {
    double worst = 0.0;
    int n = 0;
    for (auto vh : mesh.vertices()) {
      const auto p = mesh.point(vh);
      if (std::hypot(p[0] - spot_.x(), p[1] - spot_.y()) > radius) continue;
      worst = std::max(worst, std::abs(p[2] - TruthHeight(*renderer_, p[0], p[1])));
      ++n;
    }
    EXPECT_GE(n, 3) << "vertices under the flash";
    return worst;
  }
  static Reconstruction Run(double polish) {
    ReconstructionOptions options;
    options.levels = 3;
    options.start = StartSurfaceKind::kPlane;
    options.polish_robust_k = polish;
    return Reconstruct(*block_, options);
  }
  static Scene* scene_;
  static ImageBlock* block_;
  static TruthMesh* truth_;
  static Renderer* renderer_;
  static Eigen::Vector3d spot_;
};
Scene* PolishGable::scene_ = nullptr;
ImageBlock* PolishGable::block_ = nullptr;
TruthMesh* PolishGable::truth_ = nullptr;
Renderer* PolishGable::renderer_ = nullptr;
Eigen::Vector3d PolishGable::spot_ = Eigen::Vector3d::Zero();

TEST_F(PolishGable, RobustPolishRejectsAFlashAndPutsTheRoofBack) {
  const double gsd = scene_->ground_pixel_size;
  const double radius = 2.0;  // m: the vertices around the flash
  const Reconstruction plain = Run(-1.0);
  const Reconstruction polished = Run(2.0);
  const LevelReport& before = plain.report.levels.back();
  const LevelReport& after = polished.report.levels.back();
  const double worst_plain = WorstNearSpot(plain.mesh, radius);
  const double worst_polished = WorstNearSpot(polished.mesh, radius);
  std::cout << "no polish: sigma0 " << before.window.sigma0 << ", worst height error near the flash "
            << worst_plain / gsd << " GSD; polish: sigma0 " << after.window.sigma0 << " (before "
            << after.sigma0_before_polish << "), " << after.window.rejected << " rejected, "
            << after.window.downweighted << " down-weighted, worst " << worst_polished / gsd << " GSD\n";
  EXPECT_FALSE(before.polished);
  ASSERT_TRUE(after.polished);
  EXPECT_DOUBLE_EQ(after.sigma0_before_polish, before.window.sigma0);  // the same run up to the polish
  EXPECT_GT(after.window.rejected, 0);
  EXPECT_LT(after.window.sigma0, 0.8 * before.window.sigma0);
  EXPECT_LT(worst_polished, 0.5 * worst_plain);
  EXPECT_NE(polished.report.Json().find("\"sigma0_before_polish\""), std::string::npos);
}

}  // namespace
}  // namespace facets
