#include "visibility/silhouette.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "mesh/closed_surface.h"
#include "visibility/embree_scene.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

// A camera at the origin looking along +Z, 200 x 200 pixels, f = 500 px.
Camera TestCamera() {
  return Camera::Create(CameraModel::kPinhole, 500, 500, 100, 100, 200, 200);
}

// A sphere of radius 0.1 m at (dx, 0, 2) as triangles (edges of 5 mm).
void Sphere(double dx, std::vector<Eigen::Vector3d>* points,
            std::vector<Eigen::Vector3i>* triangles) {
  Ellipsoid e;
  e.centre = Eigen::Vector3d(dx, 0, 2);
  e.radii = Eigen::Vector3d::Constant(0.1);
  TinPointsAndTriangles(MakeEllipsoidMesh(e, 0.005), points, triangles);
}

// The sphere's outline seen from the camera: a disc of radius f tan(asin(r / D)) about
// the principal point (exact for the sphere on the optical axis).
ImagePlanes DiscImage(double value) {
  ImagePlanes image;
  image.width = image.height = 200;
  image.channels = 1;
  image.data.assign(200 * 200, 0.0f);
  const double radius = 500.0 * std::tan(std::asin(0.1 / 2.0));
  for (int y = 0; y < 200; ++y) {
    for (int x = 0; x < 200; ++x) {
      if (std::hypot(x + 0.5 - 100, y + 0.5 - 100) < radius) image.at(0, x, y) = value;
    }
  }
  return image;
}

double CoverageIoU(double dx, const ImagePlanes& image, const ForegroundOptions& options) {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  Sphere(dx, &points, &triangles);
  const TriangleScene scene(EmbreeDevice::Shared(), points, triangles);
  const PixelMask covered = CoverageMask(scene, TestCamera(), Rigid3d());
  return CompareMasks(ForegroundMask(image, options), covered).IoU();
}

TEST(Silhouette, SphereMatchesItsDiscAndAShiftedSphereTheTwoCircleOverlap) {
  const ImagePlanes image = DiscImage(200);
  ForegroundOptions options;
  const double same = CoverageIoU(0.0, image, options);
  EXPECT_GT(same, 0.98);
  // Shifted by one apparent radius: two circles of radius R at distance R overlap in
  // R^2 (2 pi / 3 - sqrt(3) / 2); IoU = that / (2 pi R^2 - that) = 0.2430. The shifted
  // sphere's outline is a slightly larger, slightly wider ellipse (perspective).
  const double radius_px = 500.0 * std::tan(std::asin(0.05));
  const double dx = radius_px / 500.0 * 2.0;  // lateral shift giving R pixels at Z = 2
  const double shifted = CoverageIoU(dx, image, options);
  const double overlap = 2.0 * M_PI / 3.0 - std::sqrt(3.0) / 2.0;
  const double expected = overlap / (2.0 * M_PI - overlap);
  EXPECT_NEAR(shifted, expected, 0.02) << "same " << same;
  std::printf("IoU centred %.4f, shifted %.4f (two circles %.4f)\n", same, shifted, expected);
}

TEST(Silhouette, ThresholdAndLargestComponentDropABrightSpeck) {
  ImagePlanes image = DiscImage(200);
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 20; ++x) image.at(0, x, y) = 60;  // a grey cloth in the corner
  }
  ForegroundOptions options;
  const double with_cloth = CoverageIoU(0.0, image, options);
  options.largest_component = true;
  const double largest = CoverageIoU(0.0, image, options);
  options.largest_component = false;
  options.background_max = 60;
  const double above_cloth = CoverageIoU(0.0, image, options);
  EXPECT_LT(with_cloth, 0.85);  // 400 cloth pixels against about 1960 of the disc
  EXPECT_GT(largest, 0.98);
  EXPECT_NEAR(above_cloth, largest, 1e-12);
  options.background_max = 15;
  options.min_component_pixels = 401;
  EXPECT_NEAR(CoverageIoU(0.0, image, options), largest, 1e-12);
}

TEST(Silhouette, OpeningCutsAThinBridgeAndSmallHolesAreFilled) {
  ImagePlanes image = DiscImage(200);
  for (int y = 0; y < 30; ++y) {
    for (int x = 0; x < 30; ++x) image.at(0, x, y) = 60;  // cloth
  }
  for (int i = 29; i < 100; ++i) image.at(0, i, i) = 60;  // a 1-pixel fibre to the disc
  for (int y = 98; y < 102; ++y) {
    for (int x = 98; x < 102; ++x) image.at(0, x, y) = 0;  // a dark speck inside
  }
  ForegroundOptions options;
  options.largest_component = true;
  const double bridged = CoverageIoU(0.0, image, options);
  options.open_radius = 1;
  const double opened = CoverageIoU(0.0, image, options);
  options.fill_holes_below = 50;
  const double filled = CoverageIoU(0.0, image, options);
  EXPECT_LT(bridged, 0.8);   // cloth and fibre are part of the largest component
  EXPECT_GT(opened, 0.97);   // the 16-pixel speck is still missing
  EXPECT_GT(filled, opened);
  EXPECT_GT(filled, 0.98);
  std::printf("IoU bridged %.4f, opened %.4f, filled %.4f\n", bridged, opened, filled);
}

// The signed distance to a disc's outline: at every pixel centre within 0.71 px of the
// distance to the true circle (the outline runs between pixel centres, within half a
// pixel diagonal of the circle), sign outside +, inside -; bilinear samples between the
// centres too, and their gradient points away from the centre. Measured: 0.49 px at the
// centres, 0.44 px between them, gradient within 47 degrees (25 at 2 px or more).
TEST(Silhouette, SignedDistanceToADiscOutline) {
  const int w = 160, h = 120;
  const double cx = 70.3, cy = 58.6, r = 31.7;  // pixel coordinates (centre of pixel 0 at 0.5)
  PixelMask mask(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) mask.at(x, y) = std::hypot(x + 0.5 - cx, y + 0.5 - cy) <= r ? 1 : 0;
  }
  const SilhouetteDistance field = SignedDistanceToOutline(mask);
  ASSERT_EQ(field.width, w);
  ASSERT_EQ(field.height, h);
  double worst = 0.0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double truth = std::hypot(x + 0.5 - cx, y + 0.5 - cy) - r;
      worst = std::max(worst, std::abs(field.at(x, y) - truth));
      EXPECT_EQ(field.at(x, y) < 0.0f, mask.at(x, y) == 1) << x << " " << y;
    }
  }
  EXPECT_LT(worst, 0.71);
  // Between centres, near the outline (where the gradient is that of a circle).
  // Next to the outline the pixel staircase turns the gradient by up to about 47 degrees,
  // two pixels away by up to 25.
  double worst_sample = 0.0, worst_angle = 0.0, worst_angle_far = 0.0;
  for (int k = 0; k < 72; ++k) {
    const double a = k * 5.0 * M_PI / 180.0;
    for (double off : {-2.3, -0.4, 0.6, 3.1}) {
      const Eigen::Vector2d p(cx + (r + off) * std::cos(a), cy + (r + off) * std::sin(a));
      double d = 0.0;
      Eigen::Vector2d g;
      ASSERT_TRUE(field.Sample(p, &d, &g));
      worst_sample = std::max(worst_sample, std::abs(d - off));
      const double angle = std::acos(std::clamp(g.normalized().dot(Eigen::Vector2d(std::cos(a), std::sin(a))), -1.0, 1.0));
      worst_angle = std::max(worst_angle, angle);
      if (std::abs(off) > 2.0) worst_angle_far = std::max(worst_angle_far, angle);
    }
  }
  std::cout << "signed distance: worst at pixel centres " << worst << " px, between them " << worst_sample
            << " px, gradient direction within " << worst_angle * 180.0 / M_PI << " deg ("
            << worst_angle_far * 180.0 / M_PI << " deg 2 px or more from the outline)\n";
  EXPECT_LT(worst_sample, 0.71);
  EXPECT_LT(worst_angle, 55.0 * M_PI / 180.0);
  EXPECT_LT(worst_angle_far, 30.0 * M_PI / 180.0);
  double d = 0.0;
  EXPECT_FALSE(field.Sample(Eigen::Vector2d(0.2, 10.0), &d, nullptr));
  EXPECT_FALSE(field.Sample(Eigen::Vector2d(10.0, h - 0.2), &d, nullptr));
  // An empty mask: every pixel far outside, no infinities.
  const SilhouetteDistance empty = SignedDistanceToOutline(PixelMask(8, 6));
  for (float v : empty.value) EXPECT_TRUE(std::isfinite(v) && v > 0.0f);
}

TEST(Silhouette, EvaluatesAnImageFileAndWritesJsonAndMasks) {
  const fs::path dir = fs::temp_directory_path() / ("facets_silhouette_" + std::to_string(getpid()));
  fs::create_directories(dir);
  WriteImage((dir / "disc.png").string(), DiscImage(200), 8);
  ImageBlock block;
  Camera camera = TestCamera();
  camera.camera_id = 1;
  block.cameras[1] = camera;
  BlockImage image;
  image.image_id = 1;
  image.camera_id = 1;
  image.name = "disc.png";
  image.path = (dir / "disc.png").string();
  block.images.push_back(image);
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  Sphere(0.0, &points, &triangles);
  const SilhouetteReport report =
      EvaluateSilhouettes(block, points, triangles, ForegroundOptions(), (dir / "masks").string());
  ASSERT_EQ(report.images.size(), 1u);
  EXPECT_GT(report.min_iou, 0.98);
  EXPECT_EQ(report.min_iou, report.median_iou);
  EXPECT_EQ(report.worst_image, "disc.png");
  EXPECT_TRUE(fs::exists(dir / "masks" / "disc.png"));
  const nlohmann::json j = nlohmann::json::parse(report.Json());
  EXPECT_EQ(j["images"].size(), 1u);
  EXPECT_NEAR(j["iou_min"].get<double>(), report.min_iou, 1e-12);

  block.images[0].path = (dir / "missing.png").string();
  try {
    EvaluateSilhouettes(block, points, triangles, ForegroundOptions());
    FAIL() << "no error for a missing image";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace facets
