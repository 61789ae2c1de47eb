#include "scenes/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <random>
#include <sstream>

#include "io/colmap_io.h"
#include "io/image_io.h"
#include "io/ply_io.h"
#include "scenes/camera_layout.h"

namespace facets {
namespace {
namespace fs = std::filesystem;

std::string DataPath(const std::string& name) {
  return std::string(FACETS_SOURCE_DIR) + "/scenes/data/" + name;
}

fs::path TempDir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("facets_scenes_test_" + name);
  fs::remove_all(p);
  return p;
}

// Analytic first hit of a ray on the seed gable roof (over the plane z = 0).
bool AnalyticGableHit(const Shape& roof, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                      Eigen::Vector3d* point, Eigen::Vector3d* normal) {
  const double a = roof.azimuth_deg * M_PI / 180, t = std::tan(roof.slope_deg * M_PI / 180);
  const Eigen::Vector3d eu(std::cos(a), std::sin(a), 0), ev(-std::sin(a), std::cos(a), 0);
  double best = 1e300;
  for (int side : {-1, 1}) {
    // Plane: z + side * t * v = W/2 * t, v = ev . p.
    const Eigen::Vector3d n = Eigen::Vector3d(0, 0, 1) + side * t * ev;
    const double s = (0.5 * roof.width * t - n.dot(o)) / n.dot(d);
    const Eigen::Vector3d p = o + s * d;
    const double u = eu.dot(p), v = ev.dot(p);
    if (s > 0 && s < best && side * v >= 0 && std::abs(v) <= 0.5 * roof.width &&
        std::abs(u) <= 0.5 * roof.length) {
      best = s;
      *point = p;
      *normal = n.normalized();
    }
  }
  if (best < 1e300) return true;
  const double s = -o.z() / d.z();
  *point = o + s * d;
  *normal = Eigen::Vector3d::UnitZ();
  return s > 0;
}

TEST(RendererTest, PixelEqualsAnalyticShading) {
  Scene scene = LoadScene(DataPath("seed_gable_rotated.json"));
  const TruthMesh mesh = BuildTruthMesh(scene);
  const ImageBlock block = BuildImageBlock(scene);
  const Renderer renderer(scene, mesh);
  const Eigen::Vector3d sun = scene.sun.Direction();
  double max_diff = 0, max_clean_diff = 0;
  int checked = 0;
  for (const BlockImage& image : block.images) {
    const Camera& camera = block.CameraOf(image);
    const std::vector<float> clean = renderer.RenderClean(camera, image, 1);
    const std::vector<uint8_t> grey = AddNoiseAndQuantise(clean, 0, 1);
    std::mt19937 rng(3);
    for (int k = 0; k < 300; ++k) {
      const int x = rng() % camera.width, y = rng() % camera.height;
      const Eigen::Vector3d o = image.ProjectionCentre();
      const Eigen::Vector3d d = image.cam_from_world.rotation.conjugate() *
                                camera.CamFromImage(Eigen::Vector2d(x + 0.5, y + 0.5));
      Eigen::Vector3d p, n;
      ASSERT_TRUE(AnalyticGableHit(scene.surface[1], o, d, &p, &n));
      const double expected = 255 * LambertShading(renderer.albedo()(p), n, scene.sun, sun);
      max_diff = std::max(max_diff, std::abs(grey[y * camera.width + x] - expected));
      max_clean_diff = std::max(max_clean_diff, std::abs(clean[y * camera.width + x] - expected));
      ++checked;
    }
  }
  std::cout << "checked " << checked << " pixels, max |rendered - analytic| = " << max_diff
            << " grey values (8 bit), before quantisation " << max_clean_diff << "\n";
  EXPECT_LE(max_diff, 0.5 + 1e-3);
  EXPECT_LT(max_clean_diff, 1e-3);  // float image: only float rounding remains
}

TEST(RendererTest, NoiseOfConstantPatchMatchesSigma) {
  std::istringstream in(R"({"name": "flat", "ground_pixel_size": 0.1,
    "region_of_interest": {"min": [-5,-5,-1], "max": [5,5,1]},
    "surface": [{"type": "plane", "length": 100, "width": 100}],
    "albedo": {"patches": [{"centre": [0,0,0], "size": [100,100], "albedo": 0.5}]},
    "sun": {"azimuth_deg": 0, "elevation_deg": 90, "ambient": 0.2},
    "cameras": {"type": "list", "focal_mm": 10, "pixel_um": 10, "width": 200, "height": 150,
                "cameras": [{"centre": [0,0,50], "target": [0,0,0]}]},
    "noise_sigma": 4, "supersampling": 2})");
  const Scene scene = ParseScene(in, "flat");
  const TruthMesh mesh = BuildTruthMesh(scene);
  const ImageBlock block = BuildImageBlock(scene);
  const Renderer renderer(scene, mesh);
  const Camera& camera = block.CameraOf(block.images[0]);
  const std::vector<uint8_t> grey =
      AddNoiseAndQuantise(renderer.RenderClean(camera, block.images[0], 2), 4, 42);
  double sum = 0, sum_sq = 0;
  for (uint8_t g : grey) {
    sum += g;
    sum_sq += double(g) * g;
  }
  const double mean = sum / grey.size();
  const double sigma = std::sqrt(sum_sq / grey.size() - mean * mean);
  std::cout << "constant patch: mean " << mean << " (expected " << 255 * 0.5 << "), sigma "
            << sigma << " (expected 4)\n";
  EXPECT_NEAR(mean, 127.5, 0.2);
  EXPECT_NEAR(sigma, 4.0, 0.4);
}

// A 10 m cube on flat ground, sun from the east at 45 degrees: ground 3 m west of the
// cube lies in its shadow (the ray to the sun meets the west wall 3 m up), ground 15 m
// west is lit (the ray passes 15 m up, above the 10 m roof).
TEST(RendererTest, CastShadowsLeaveTheAmbientLightOnly) {
  const std::string json = R"({
    "name": "shadow", "ground_pixel_size": 0.1,
    "region_of_interest": {"min": [-30, -10, -1], "max": [10, 10, 11]},
    "surface": [{"type": "terrain", "length": 80, "width": 80},
                {"type": "building", "roof": "flat", "length": 10, "width": 10, "height": 10}],
    "sun": {"azimuth_deg": 90, "elevation_deg": 45, "ambient": 0.2, "cast_shadows": CAST},
    "cameras": {"type": "list", "focal_mm": 10, "pixel_um": 10, "width": 200, "height": 150,
                "cameras": [{"centre": [0,0,50], "target": [0,0,0]}]}})";
  for (const bool cast : {false, true}) {
    std::string text = json;
    text.replace(text.find("CAST"), 4, cast ? "true" : "false");
    std::istringstream in(text);
    const Scene scene = ParseScene(in, "shadow");
    const TruthMesh mesh = BuildTruthMesh(scene);
    const Renderer renderer(scene, mesh);
    const double lit = 0.2 + 0.8 * std::sqrt(0.5);  // ambient + (1 - ambient) sin 45 deg
    for (const double x : {-8.0, -20.0}) {
      const SurfaceHit hit = renderer.Cast(Eigen::Vector3d(x, 0, 50), -Eigen::Vector3d::UnitZ());
      ASSERT_TRUE(hit.hit);
      ASSERT_NEAR(hit.point.z(), 0, 1e-9);
      const double albedo = renderer.albedo()(hit.point);
      const bool in_shadow = cast && x == -8.0;
      EXPECT_NEAR(renderer.Radiance(hit), 255 * albedo * (in_shadow ? 0.2 : lit), 1e-9)
          << "x " << x << " cast_shadows " << cast;
    }
  }
}

TEST(RendererTest, TiePointsProjectOntoTheirObservations) {
  const Scene scene = LoadScene(DataPath("block.json"));
  const TruthMesh mesh = BuildTruthMesh(scene);
  ImageBlock block = BuildImageBlock(scene);
  const Renderer renderer(scene, mesh);
  const int n = SampleTiePoints(scene, mesh, renderer, 7, &block);
  double max_px = 0, sum_px = 0;
  int observations = 0;
  size_t max_track = 0;
  for (const TiePoint& tie : block.points) {
    EXPECT_GE(tie.track.size(), 2u);
    max_track = std::max(max_track, tie.track.size());
    for (const TrackElement& t : tie.track) {
      const BlockImage& image = block.images[t.image_id - 1];
      const Camera& camera = block.CameraOf(image);
      const Keypoint& kp = image.keypoints[t.point2d_idx];
      EXPECT_EQ(kp.point3d_id, tie.point3d_id);
      EXPECT_TRUE(kp.xy.x() > 0 && kp.xy.y() > 0 && kp.xy.x() < camera.width &&
                  kp.xy.y() < camera.height);
      const double d = (camera.ImageFromCam(image.cam_from_world * tie.xyz) - kp.xy).norm();
      max_px = std::max(max_px, d);
      sum_px += d;
      ++observations;
    }
  }
  std::cout << n << " tie points, " << observations << " observations, longest track "
            << max_track << ", reprojection of perturbed xyz: mean " << sum_px / observations
            << " px, max " << max_px << " px\n";
  EXPECT_EQ(n, scene.tie_points);
  EXPECT_LT(max_px, 1.0);
}

std::string ReadBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(RendererTest, RenderSceneIsDeterministicAndReadsBack) {
  const Scene scene = LoadScene(DataPath("seed_cylinder_parallel_patch.json"));
  const fs::path a = TempDir("a"), b = TempDir("b"), c = TempDir("c");
  const RenderSummary sa = RenderScene(scene, a.string());
  RenderScene(scene, b.string());
  RenderOptions other;
  other.seed = 2;
  RenderScene(scene, c.string(), other);
  std::cout << "rendered " << sa.images << " images, " << sa.pixels << " pixels, "
            << sa.tie_points << " tie points in " << sa.seconds << " s\n";
  for (const char* f : {"images/img_00.png", "images/img_01.png", "sparse/images.txt",
                        "sparse/points3D.txt", "truth.ply", "project.json", "truth.json"}) {
    EXPECT_EQ(ReadBytes(a / f), ReadBytes(b / f)) << f;
  }
  EXPECT_NE(ReadBytes(a / "images/img_00.png"), ReadBytes(c / "images/img_00.png"));

  const ImageBlock block = ReadColmapModel((a / "sparse").string(), (a / "images").string());
  const ImageBlock truth = BuildImageBlock(scene);
  ASSERT_EQ(block.images.size(), 2u);
  EXPECT_EQ(static_cast<int>(block.points.size()), sa.tie_points);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_LT((block.images[i].ProjectionCentre() - truth.images[i].ProjectionCentre()).norm(),
              1e-9);
    const Camera& cam = block.CameraOf(block.images[i]);
    EXPECT_EQ(cam.width, truth.CameraOf(truth.images[i]).width);
    EXPECT_NEAR(cam.PrincipalX(), truth.CameraOf(truth.images[i]).PrincipalX(), 1e-9);
    const ImagePlanes img = ReadImageFor(block.images[i].path, cam);
    EXPECT_EQ(img.channels, 1);
  }
  const MeshData ply = ReadPly((a / "truth.ply").string());
  const TruthMesh mesh = BuildTruthMesh(scene);
  EXPECT_EQ(ply.faces.size(), mesh.faces.size());
  EXPECT_EQ(ply.face_labels, mesh.labels);
  EXPECT_TRUE(fs::exists(a / "scene.json"));
  for (const auto& p : {a, b, c}) fs::remove_all(p);
}

}  // namespace
}  // namespace facets

namespace facets {
namespace {

TEST(AlbedoTest, FastSinMatchesStdSin) {
  double max_err = 0;
  for (int i = -2000000; i <= 2000000; ++i) {
    const double x = i * 0.0037;  // |x| up to 7400 rad (texture phases over ~200 m)
    max_err = std::max(max_err, std::abs(FastSin(x) - std::sin(x)));
  }
  std::cout << "FastSin max error " << max_err << "\n";
  EXPECT_LT(max_err, 1e-9);
}

}  // namespace
}  // namespace facets
