// The geometry check on the bundled block scene (13 images: 3 x 3 nadir, 4 obliques) and
// the seed stereo pair, with one image's pose or camera corrupted at a time as a careless
// export would: the image is named and dropped, the rest passes unchanged; a block left
// with fewer than 2 usable images stops with the reasons. The real sets pass whole.
#include "engine/pipeline/geometry_check.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/pipeline/reconstruction.h"
#include "engine/pipeline/start_stage.h"
#include "io/image_io.h"
#include "io/colmap_io.h"
#include "io/shared_data_for_testing.h"
#include "scenes/camera_layout.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"

namespace facets {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The block RenderScene writes for a bundled scene (the same layout, tie-point sampling
// and seed: cameras, poses, tie points with their 2D observations, region), without
// rendering its images: the check reads no pixel.
ImageBlock SceneBlock(const std::string& scene_file) {
  const Scene scene = LoadScene(std::string(FACETS_SOURCE_DIR) + "/" + scene_file);
  const TruthMesh mesh = BuildTruthMesh(scene);
  ImageBlock block = BuildImageBlock(scene);
  const Renderer renderer(scene, mesh);
  SampleTiePoints(scene, mesh, renderer, static_cast<uint32_t>(scene.seed) * 7u + 1u, &block);
  block.roi = scene.roi;
  return block;
}

const ImageBlock& Block() {
  static const ImageBlock block = SceneBlock("scenes/data/block.json");
  return block;
}

const ImageBlock& Pair() {
  static const ImageBlock pair = SceneBlock("scenes/data/seed_gable_parallel.json");
  return pair;
}

GeometryCheck Check(const ImageBlock& block) { return CheckBlockGeometry(block, *block.roi); }

// The message of the std::runtime_error `run` throws; "" when it throws none.
std::string ErrorOf(const std::function<void()>& run) {
  try {
    run();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::string AllLines(const GeometryCheck& check) {
  std::string text;
  for (const std::string& line : check.Lines()) text += line + "\n";
  return text;
}

// Rotates the image 180 degrees about its own axis (0 0 1: about the optical axis, the
// region still in view; 1 0 0: looking away), the projection centre kept.
void Rotate180(BlockImage* image, const Eigen::Vector3d& axis) {
  const Eigen::Vector3d centre = image->ProjectionCentre();
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(kPi, axis));
  image->cam_from_world.rotation = turn * image->cam_from_world.rotation;
  image->cam_from_world.translation = -(image->cam_from_world.rotation * centre);
}

// The image gets its own copy of its camera (id 100), changed by `change`.
void ChangeOwnCamera(ImageBlock* block, BlockImage* image, const std::function<void(Camera*)>& change) {
  Camera camera = block->CameraOf(*image);
  camera.camera_id = 100;
  change(&camera);
  block->cameras[100] = camera;
  image->camera_id = 100;
}

Camera WithRadialDistortion(const Camera& pinhole, double k1) {
  Camera camera = Camera::Create(CameraModel::kSimpleRadial, pinhole.FocalX(), pinhole.FocalY(), pinhole.PrincipalX(),
                                 pinhole.PrincipalY(), pinhole.width, pinhole.height);
  camera.camera_id = pinhole.camera_id;
  camera.params[3] = k1;
  return camera;
}

struct Corruption {
  const char* what;
  std::function<void(ImageBlock*, BlockImage*)> apply;
  const char* named_problem;  // expected in the dropped image's warning
};

std::vector<Corruption> Corruptions() {
  return {
      {"rotated 180 deg about the optical axis",
       [](ImageBlock*, BlockImage* image) { Rotate180(image, Eigen::Vector3d::UnitZ()); }, "reproject with a median"},
      {"rotated 180 deg about its x axis",
       [](ImageBlock*, BlockImage* image) { Rotate180(image, Eigen::Vector3d::UnitX()); }, "the region lies behind it"},
      {"moved 2 km along X",
       [](ImageBlock*, BlockImage* image) {
         image->cam_from_world.translation -= image->cam_from_world.rotation * Eigen::Vector3d(2000, 0, 0);
       },
       "the region lies outside its frame"},
      {"translation 1e308",
       [](ImageBlock*, BlockImage* image) { image->cam_from_world.translation.x() = 1e308; },
       "its translation (1e+308"},
      {"rotation NaN",
       [](ImageBlock*, BlockImage* image) {
         image->cam_from_world.rotation.w() = std::numeric_limits<double>::quiet_NaN();
       },
       "its rotation is not finite"},
      {"focal length 1e308",
       [](ImageBlock* block, BlockImage* image) {
         ChangeOwnCamera(block, image, [](Camera* camera) { camera->params[0] = camera->params[1] = 1e308; });
       },
       "camera 100 (PINHOLE): focal length 1e+308 px is absurd"},
      {"k1 = 1e6",
       [](ImageBlock* block, BlockImage* image) {
         ChangeOwnCamera(block, image, [](Camera* camera) { *camera = WithRadialDistortion(*camera, 1e6); });
       },
       "camera 100 (SIMPLE_RADIAL): the lens distortion scales the radius"},
  };
}

TEST(GeometryCheck, CleanBlockPassesWithSmallReprojection) {
  const ImageBlock& block = Block();
  ASSERT_EQ(block.images.size(), 13u);
  const GeometryCheck check = Check(block);
  const std::string lines = AllLines(check);
  std::printf("%s", lines.c_str());
  EXPECT_EQ(check.UsableCount(), 13);
  EXPECT_EQ(check.Lines().size(), 1u) << lines;  // the summary, no warning
  EXPECT_EQ(lines.find("warning"), std::string::npos);
  EXPECT_GT(check.observations, 1000);
  // Tie points are the truth perturbed by a quarter ground pixel (scenes/scene.h):
  // measured 0.23 px median, worst image 0.26 px.
  EXPECT_LT(check.median_reprojection_px, 0.4);
  ASSERT_GE(check.worst_image, 0);
  EXPECT_LT(check.images[check.worst_image].median_reprojection_px, 0.5);
  EXPECT_EQ(check.bad_image_median_px, 5.0);
  for (const ImageGeometry& image : check.images) EXPECT_GE(image.region_points_stereo, 3) << image.name;
  EXPECT_EQ(KeepUsableImages(block, check).images.size(), 13u);
}

// Each corruption of image 5 (img_04.png, the centre nadir image): named in one warning,
// dropped, and the block kept is the clean block without it.
TEST(GeometryCheck, CorruptedImageIsNamedAndDropped) {
  for (const Corruption& corruption : Corruptions()) {
    SCOPED_TRACE(corruption.what);
    ImageBlock block = Block();
    BlockImage& bad = block.images[4];
    ASSERT_EQ(bad.name, "img_04.png");
    corruption.apply(&block, &bad);
    const GeometryCheck check = Check(block);
    const std::vector<std::string> lines = check.Lines();
    std::printf("%s:\n%s", corruption.what, AllLines(check).c_str());
    EXPECT_EQ(check.UsableCount(), 12);
    ASSERT_EQ(lines.size(), 2u);
    EXPECT_EQ(lines[1].rfind("warning: image 5 (img_04.png) dropped: ", 0), 0u) << lines[1];
    EXPECT_NE(lines[1].find(corruption.named_problem), std::string::npos) << lines[1];
    const ImageBlock kept = KeepUsableImages(block, check);
    ASSERT_EQ(kept.images.size(), 12u);
    EXPECT_EQ(kept.cameras.size(), 1u);
    for (const BlockImage& image : kept.images) EXPECT_NE(image.name, "img_04.png");
    long long observations = 0, clean_observations = 0;
    for (const TiePoint& point : kept.points) {
      for (const TrackElement& element : point.track) {
        EXPECT_NE(element.image_id, 5);
        ++observations;
      }
    }
    for (const TiePoint& point : Block().points) {
      for (const TrackElement& element : point.track) clean_observations += element.image_id != 5;
    }
    EXPECT_EQ(observations, clean_observations);
  }
}

TEST(GeometryCheck, TwoEntriesNamingOneFileAreAnError) {
  ImageBlock block = Block();
  block.images[7].name = block.images[3].name;
  EXPECT_EQ(ErrorOf([&] { Check(block); }),
            "img_03.png: named by two images, image 4 (img_03.png) and image 8 (img_03.png); each image file "
            "may appear once in a block");
}

// The stereo pair with one image corrupted: the other has no partner left, the run stops.
TEST(GeometryCheck, PairWithOneBadImageStopsNamingBoth) {
  ImageBlock pair = Pair();
  ASSERT_EQ(pair.images.size(), 2u);
  const GeometryCheck clean = Check(pair);
  std::printf("clean pair: %s\n", clean.Lines()[0].c_str());
  EXPECT_EQ(clean.UsableCount(), 2);
  Rotate180(&pair.images[1], Eigen::Vector3d::UnitZ());
  const GeometryCheck check = Check(pair);
  EXPECT_EQ(check.UsableCount(), 0);
  const std::string what = ErrorOf([&] { KeepUsableImages(pair, check); });
  std::printf("%s\n", what.c_str());
  EXPECT_EQ(what.rfind("geometry check: 0 of 2 images usable, a surface needs at least 2", 0), 0u) << what;
  // The pair's frames are cut to the region (their principal points lie outside them):
  // turned about its axis, the image looks beside the region.
  EXPECT_NE(what.find("image 2 (img_01.png): it sees 0 of the region's 247 points"), std::string::npos) << what;
  EXPECT_NE(what.find("tie-point observations reproject with a median of"), std::string::npos) << what;
  EXPECT_NE(what.find("image 1 (img_00.png): no other usable image sees its region points"), std::string::npos)
      << what;
}

// Two images from (almost) one place see the region, but their rays meet at under 2 deg.
TEST(GeometryCheck, RegionSeenFromOnePlaceOnlyStops) {
  ImageBlock pair = Pair();
  const Eigen::Vector3d centre = pair.images[0].ProjectionCentre() + Eigen::Vector3d(20, 0, 0);
  pair.images[1].cam_from_world = pair.images[0].cam_from_world;
  pair.images[1].cam_from_world.translation = -(pair.images[1].cam_from_world.rotation * centre);
  pair.images[1].camera_id = pair.images[0].camera_id;
  for (TiePoint& point : pair.points) point.track.clear();  // no observations fit the moved image
  const GeometryCheck check = Check(pair);
  for (const ImageGeometry& image : check.images) {
    EXPECT_GT(image.region_points_seen, 100) << image.name;
    EXPECT_EQ(image.region_points_stereo, 0) << image.name;
  }
  EXPECT_THROW(KeepUsableImages(pair, check), std::runtime_error);
}

// The block's one camera with k1 = 1e6: every image is unusable, the camera is named.
TEST(GeometryCheck, SharedCameraCorruptedStopsNamingIt) {
  ImageBlock block = Block();
  block.cameras[1] = WithRadialDistortion(block.cameras[1], 1e6);
  const GeometryCheck check = Check(block);
  EXPECT_EQ(check.UsableCount(), 0);
  const std::string what = ErrorOf([&] { KeepUsableImages(block, check); });
  EXPECT_NE(what.find("image 13 (img_12.png): camera 1 (SIMPLE_RADIAL): the lens distortion"), std::string::npos)
      << what;
}

// Reconstruct() called as a library runs the checks itself, the image files first: the
// pair with one image turned stops with the geometry check's reasons before any pixel
// is read (the images are blank); a missing file, or one of the wrong size, is named
// before the geometry is looked at.
TEST(GeometryCheck, ReconstructRunsTheChecksImageFilesFirst) {
  ImageBlock pair = Pair();
  const std::filesystem::path dir =
      std::filesystem::path(testing::TempDir()) / ("facets_geometry_check_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  for (BlockImage& image : pair.images) {
    const Camera& camera = pair.CameraOf(image);
    ImagePlanes blank;
    blank.width = camera.width;
    blank.height = camera.height;
    blank.channels = 1;
    blank.data.assign(static_cast<size_t>(camera.width) * camera.height, 0.0f);
    image.path = (dir / image.name).string();
    WriteImage(image.path, blank);
  }
  Rotate180(&pair.images[1], Eigen::Vector3d::UnitZ());
  ReconstructionOptions options;
  std::vector<std::string> said;
  options.progress = [&said](const std::string& line) { said.push_back(line); };
  const std::string geometry = ErrorOf([&] { Reconstruct(pair, options); });
  EXPECT_EQ(geometry.rfind("geometry check: 0 of 2 images usable, a surface needs at least 2", 0), 0u) << geometry;
  ASSERT_FALSE(said.empty());
  EXPECT_EQ(said.front().rfind("geometry check: 0 of 2 images usable", 0), 0u) << said.front();

  const std::string first = pair.images[0].path;
  std::filesystem::remove(first);
  const std::string missing = ErrorOf([&] { Reconstruct(pair, options); });
  EXPECT_EQ(missing.rfind(first + ": image file not found", 0), 0u) << missing;
  ImagePlanes small;
  small.width = small.height = small.channels = 1;
  small.data = {0.0f};
  WriteImage(first, small);
  const std::string size = ErrorOf([&] { Reconstruct(pair, options); });
  EXPECT_NE(size.find(first + ": image is 1x1 pixels but camera"), std::string::npos) << size;
  std::filesystem::remove_all(dir);
}

// The real sets (kite aerials, a facade from the street, an object all around) keep every
// image with their tie points' region.
TEST(GeometryCheck, RealSetsPassWhole) {
  for (const char* set : {"boruszyn_kap/sparse_georef_local2180", "strecha_fountain-P11/sparse_with_points",
                          "middlebury_templeSparseRing/sparse_with_points"}) {
    FACETS_SKIP_WITHOUT_SHARED_DATA(set);
    const ImageBlock block = ReadColmapModel(SharedDataDir() + set);
    const GeometryCheck check = CheckBlockGeometry(block, ChooseRegion(block, std::nullopt));
    const ImageBlock kept = KeepUsableImages(block, check);
    std::printf("%s: %s\n", set, AllLines(check).c_str());
    EXPECT_EQ(kept.images.size(), block.images.size()) << AllLines(check);
    EXPECT_EQ(check.Lines().size(), 1u) << AllLines(check);
  }
}

}  // namespace
}  // namespace facets
