#include "io/colmap_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <locale>
#include <sstream>
#include <stdexcept>

#include "io/shared_data_for_testing.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

const std::string kData = SharedDataDir();

struct ModelCounts {
  int cameras = 0, images = 0, points = 0;
};

// Counted without the reader: data lines of cameras.txt and points3D.txt; lines of
// images.txt that are not comments, two per image (the 2D line may be empty).
ModelCounts CountLines(const std::string& sparse_dir) {
  ModelCounts counts;
  auto count = [](const std::string& path, bool keep_empty) {
    std::ifstream in(path);
    EXPECT_TRUE(in.good()) << path;
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      if (!line.empty() && line[0] == '#') continue;
      if (line.empty() && !keep_empty) continue;
      ++n;
    }
    return n;
  };
  counts.cameras = count(sparse_dir + "/cameras.txt", false);
  const int image_lines = count(sparse_dir + "/images.txt", true);
  EXPECT_EQ(image_lines % 2, 0) << sparse_dir;
  counts.images = image_lines / 2;
  counts.points = count(sparse_dir + "/points3D.txt", false);
  return counts;
}

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("facets_io_test_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Mean distance between each tie point projected into the images of its track and
// the 2D point it was measured at: checks the pose convention end to end.
double MeanReprojectionError(const ImageBlock& block, int* observations) {
  std::map<int, const BlockImage*> by_id;
  for (const auto& image : block.images) by_id[image.image_id] = &image;
  double sum = 0;
  int n = 0;
  for (const TiePoint& point : block.points) {
    for (const TrackElement& element : point.track) {
      const BlockImage& image = *by_id.at(element.image_id);
      const Eigen::Vector3d point_in_cam = image.cam_from_world * point.xyz;
      EXPECT_GT(point_in_cam.z(), 0);
      const Eigen::Vector2d projected = block.CameraOf(image).ImageFromCam(point_in_cam);
      sum += (projected - image.keypoints.at(element.point2d_idx).xy).norm();
      ++n;
    }
  }
  *observations = n;
  return n ? sum / n : 0.0;
}

struct RealModel {
  const char* sparse;
  const char* images;
  const char* model;
  double max_mean_reprojection_px;
};

TEST(ColmapIoTest, ReadsTheRealModels) {
  const RealModel models[] = {
      {"boruszyn_kap/sparse_georef_local2180", "boruszyn_kap/images", "SIMPLE_RADIAL", 1.0},
      {"strecha_fountain-P11/sparse", "strecha_fountain-P11/images", "PINHOLE", 0},
      {"strecha_fountain-P11/sparse_with_points", "strecha_fountain-P11/images", "PINHOLE", 1.5},
      {"middlebury_templeSparseRing/sparse", "middlebury_templeSparseRing/images", "PINHOLE", 0},
      {"middlebury_templeSparseRing/sparse_with_points", "middlebury_templeSparseRing/images",
       "PINHOLE", 1.5},
  };
  for (const RealModel& m : models) {
    FACETS_SKIP_WITHOUT_SHARED_DATA(m.sparse);
    FACETS_SKIP_WITHOUT_SHARED_DATA(m.images);
  }
  for (const RealModel& m : models) {
    const std::string sparse = kData + m.sparse;
    const ModelCounts expected = CountLines(sparse);
    const ImageBlock block = ReadColmapModel(sparse, kData + m.images);
    int observations = 0;
    const double reprojection = MeanReprojectionError(block, &observations);
    std::cout << m.sparse << ": " << block.cameras.size() << " cameras, " << block.images.size()
              << " images, " << block.points.size() << " points (files: " << expected.cameras
              << ", " << expected.images << ", " << expected.points << "), " << observations
              << " observations, mean reprojection error " << reprojection << " px\n";
    EXPECT_EQ(static_cast<int>(block.cameras.size()), expected.cameras) << m.sparse;
    EXPECT_EQ(static_cast<int>(block.images.size()), expected.images) << m.sparse;
    EXPECT_EQ(static_cast<int>(block.points.size()), expected.points) << m.sparse;
    EXPECT_GT(block.images.size(), 10u);
    EXPECT_EQ(block.origin, Eigen::Vector3d::Zero());
    for (const auto& [id, camera] : block.cameras) {
      EXPECT_EQ(CameraModelName(camera.model), m.model) << m.sparse;
    }
    for (const BlockImage& image : block.images) {
      EXPECT_TRUE(block.cameras.count(image.camera_id)) << m.sparse << " " << image.name;
      EXPECT_TRUE(fs::is_regular_file(image.path)) << image.path;
      EXPECT_NEAR(image.cam_from_world.rotation.norm(), 1.0, 1e-12);
    }
    if (m.max_mean_reprojection_px > 0) {
      EXPECT_GT(observations, 1000) << m.sparse;
      EXPECT_LT(reprojection, m.max_mean_reprojection_px) << m.sparse;
    }
  }
}

TEST(ColmapIoTest, BoruszynDetails) {
  FACETS_SKIP_WITHOUT_SHARED_DATA("boruszyn_kap/sparse_georef_local2180");
  const ImageBlock block = ReadColmapModel(kData + "boruszyn_kap/sparse_georef_local2180");
  ASSERT_EQ(block.cameras.size(), 1u);
  const Camera& camera = block.cameras.at(1);
  EXPECT_EQ(camera.width, 1152);
  EXPECT_EQ(camera.height, 864);
  EXPECT_DOUBLE_EQ(camera.params[0], 942.86985899807928);
  EXPECT_DOUBLE_EQ(camera.params[3], -0.038744509714348535);
  // First image line of images.txt: id 28, name img_4977.jpg, path unresolved.
  EXPECT_EQ(block.images.front().image_id, 28);
  EXPECT_EQ(block.images.front().name, "img_4977.jpg");
  EXPECT_TRUE(block.images.front().path.empty());
  EXPECT_DOUBLE_EQ(block.images.front().cam_from_world.translation.z(), 136.95340483265829);
  // Kite photos 70-300 m above ground, Z up: every projection centre is above every
  // tie point's median height.
  std::vector<double> heights;
  for (const auto& p : block.points) heights.push_back(p.xyz.z());
  std::nth_element(heights.begin(), heights.begin() + heights.size() / 2, heights.end());
  const double median = heights[heights.size() / 2];
  for (const auto& image : block.images) {
    EXPECT_GT(image.ProjectionCentre().z() - median, 50.0) << image.name;
  }
}

TEST(ColmapIoTest, WriteReadRoundTripIsExact) {
  FACETS_SKIP_WITHOUT_SHARED_DATA("boruszyn_kap/sparse_georef_local2180");
  const ImageBlock block = ReadColmapModel(kData + "boruszyn_kap/sparse_georef_local2180");
  const fs::path dir = TempDir("colmap_roundtrip") / "sparse";
  WriteColmapModel(block, dir.string());
  for (const char* f : {"cameras.txt", "images.txt", "points3D.txt"}) {
    EXPECT_TRUE(fs::exists(dir / f)) << f;
    EXPECT_FALSE(fs::exists(dir / (std::string(f) + ".tmp"))) << f;
  }
  const ImageBlock again = ReadColmapModel(dir.string());
  ASSERT_EQ(again.cameras.size(), block.cameras.size());
  ASSERT_EQ(again.images.size(), block.images.size());
  ASSERT_EQ(again.points.size(), block.points.size());
  EXPECT_EQ(again.cameras.at(1).params, block.cameras.at(1).params);
  size_t keypoints = 0;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& a = block.images[i];
    const BlockImage& b = again.images[i];
    EXPECT_EQ(a.image_id, b.image_id);
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.camera_id, b.camera_id);
    EXPECT_EQ(a.cam_from_world.rotation.coeffs(), b.cam_from_world.rotation.coeffs());
    EXPECT_EQ(a.cam_from_world.translation, b.cam_from_world.translation);
    ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
    for (size_t k = 0; k < a.keypoints.size(); ++k) {
      EXPECT_EQ(a.keypoints[k].xy, b.keypoints[k].xy);
      EXPECT_EQ(a.keypoints[k].point3d_id, b.keypoints[k].point3d_id);
    }
    keypoints += a.keypoints.size();
  }
  for (size_t i = 0; i < block.points.size(); ++i) {
    EXPECT_EQ(block.points[i].point3d_id, again.points[i].point3d_id);
    EXPECT_EQ(block.points[i].xyz, again.points[i].xyz);
    EXPECT_EQ(block.points[i].rgb, again.points[i].rgb);
    EXPECT_EQ(block.points[i].error, again.points[i].error);
    ASSERT_EQ(block.points[i].track.size(), again.points[i].track.size());
  }
  std::cout << "round trip bit-exact over " << block.images.size() << " images, " << keypoints
            << " 2D points, " << block.points.size() << " 3D points\n";
  fs::remove_all(dir.parent_path());
}

TEST(ColmapIoTest, MissingImageFileIsNamed) {
  FACETS_SKIP_WITHOUT_SHARED_DATA("strecha_fountain-P11/sparse");
  const fs::path dir = TempDir("colmap_missing_image");
  try {
    ReadColmapModel(kData + "strecha_fountain-P11/sparse", dir.string());
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    std::cout << "error: " << what << "\n";
    EXPECT_NE(what.find((dir / "0000.jpg").string()), std::string::npos) << what;
  }
  EXPECT_THROW(ReadColmapModel(dir.string()), std::runtime_error);  // no cameras.txt
  EXPECT_THROW(ReadColmapModel((dir / "nope").string()), std::runtime_error);
  fs::remove_all(dir);
}

const char* kCameras =
    "# comment\n"
    "1 PINHOLE 640 480 500 501 320 240\n"
    "2 SIMPLE_RADIAL 800 600 700 400 300 -0.01\r\n";
const char* kImages =
    "# IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
    "1 1 0 0 0 0.5 -0.25 10 1 a.png\n"
    "100 200 -1 110 210 0\n"
    "2 0.7071067811865476 0 0.7071067811865476 0 1 2 3 2 sub dir/b 2.png\n"
    "\n";
const char* kPoints =
    "# POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[]\n"
    "0 1.5 2.5 3.5 10 20 30 0.25 1 1\n";

ImageBlock ReadStrings(const std::string& cameras, const std::string& images,
                       const std::string& points = "") {
  std::istringstream c(cameras), i(images), p(points);
  return ReadColmapModel(c, i, points.empty() ? nullptr : &p, "test");
}

// The error message of reading the given texts, "" when none.
std::string ErrorOf(const std::string& cameras, const std::string& images,
                    const std::string& points = "") {
  try {
    ReadStrings(cameras, images, points);
  } catch (const std::runtime_error& e) {
    std::cout << "  error: " << e.what() << "\n";
    return e.what();
  }
  return "";
}

TEST(ColmapIoTest, ParsesStreams) {
  const ImageBlock block = ReadStrings(kCameras, kImages, kPoints);
  ASSERT_EQ(block.cameras.size(), 2u);
  ASSERT_EQ(block.images.size(), 2u);
  ASSERT_EQ(block.points.size(), 1u);
  EXPECT_EQ(block.cameras.at(2).model, CameraModel::kSimpleRadial);
  EXPECT_DOUBLE_EQ(block.cameras.at(2).params[3], -0.01);
  EXPECT_EQ(block.images[0].keypoints.size(), 2u);
  EXPECT_EQ(block.images[0].keypoints[0].xy, Eigen::Vector2d(100, 200));
  EXPECT_EQ(block.images[0].keypoints[0].point3d_id, -1);
  EXPECT_EQ(block.images[0].keypoints[1].point3d_id, 0);
  EXPECT_EQ(block.images[1].name, "sub dir/b 2.png");
  EXPECT_TRUE(block.images[1].keypoints.empty());
  // cam_from_world is taken as it is: the projection centre is -R^T t.
  EXPECT_TRUE(block.images[0].ProjectionCentre().isApprox(Eigen::Vector3d(-0.5, 0.25, -10)));
  const Eigen::Vector3d c2 = block.images[1].ProjectionCentre();
  EXPECT_NEAR((block.images[1].cam_from_world * c2).norm(), 0, 1e-12);
  EXPECT_EQ(block.points[0].xyz, Eigen::Vector3d(1.5, 2.5, 3.5));
  EXPECT_EQ(block.points[0].rgb, Eigen::Vector3i(10, 20, 30));
  ASSERT_EQ(block.points[0].track.size(), 1u);
  EXPECT_EQ(block.points[0].track[0].image_id, 1);
  EXPECT_EQ(block.points[0].track[0].point2d_idx, 1);
}

TEST(ColmapIoTest, RejectsBadInputWithFileLineAndReason) {
  std::string e;
  e = ErrorOf("# c\n1 FISHEYE 640 480 500 320 240\n", kImages);
  EXPECT_NE(e.find("test/cameras.txt:2"), std::string::npos);
  EXPECT_NE(e.find("FISHEYE"), std::string::npos);

  e = ErrorOf("1 PINHOLE 640 480 500 320 240\n", kImages);
  EXPECT_NE(e.find("cameras.txt:1"), std::string::npos);
  EXPECT_NE(e.find("needs 4 parameters, got 3"), std::string::npos);

  e = ErrorOf("1 PINHOLE 640 480 500 nan 320 240\n", kImages);
  EXPECT_NE(e.find("not finite"), std::string::npos);

  e = ErrorOf("1 PINHOLE 640 480 500 5,5 320 240\n", kImages);
  EXPECT_NE(e.find("not a number ('5,5')"), std::string::npos);

  e = ErrorOf("1 PINHOLE 0 480 500 500 320 240\n", kImages);
  EXPECT_NE(e.find("size must be positive"), std::string::npos);

  e = ErrorOf("1 PINHOLE 640\n", kImages);
  EXPECT_NE(e.find("truncated"), std::string::npos);

  e = ErrorOf(std::string(kCameras) + "2 PINHOLE 640 480 500 500 320 240\n", kImages);
  EXPECT_NE(e.find("cameras.txt:4: duplicate CAMERA_ID 2"), std::string::npos);

  e = ErrorOf(kCameras, "1 1 0 0 0 NaN 0 10 1 a.png\n\n");
  EXPECT_NE(e.find("images.txt:1: TX is not finite"), std::string::npos);

  e = ErrorOf(kCameras, "1 1 0 0 0 0 0 inf 1 a.png\n\n");
  EXPECT_NE(e.find("TZ is not finite"), std::string::npos);

  e = ErrorOf(kCameras, "1 0 0 0 0 0 0 1 1 a.png\n\n");
  EXPECT_NE(e.find("zero length"), std::string::npos);

  e = ErrorOf(kCameras, "# x\n1 1 0 0 0 0 0 1 9 a.png\n\n");
  EXPECT_NE(e.find("images.txt:2: image 1 refers to unknown CAMERA_ID 9"), std::string::npos);

  e = ErrorOf(kCameras, "1 1 0 0 0 0 0 1 1 a.png\n\n1 1 0 0 0 0 0 1 1 b.png\n\n");
  EXPECT_NE(e.find("images.txt:3: duplicate IMAGE_ID 1"), std::string::npos);

  e = ErrorOf(kCameras, "1 1 0 0 0 0 0 1 1\n\n");
  EXPECT_NE(e.find("images.txt:1: truncated"), std::string::npos);

  e = ErrorOf(kCameras, "1 1 0 0 0 0 0 1 1 a.png\n1 2 -1 4\n");
  EXPECT_NE(e.find("images.txt:2: POINTS2D"), std::string::npos);

  e = ErrorOf(kCameras, "1 1 0 0 0 0 0 1 1 a.png\n1 2 x\n");
  EXPECT_NE(e.find("POINT3D_ID of 2D point 0 is not an integer"), std::string::npos);

  e = ErrorOf(kCameras, kImages, "0 1 2 3 1 2 3 0.5 7 0\n");
  EXPECT_NE(e.find("points3D.txt:1: track refers to unknown IMAGE_ID 7"), std::string::npos);

  e = ErrorOf(kCameras, kImages, "0 1 2 3 1 2 3 0.5 1 5\n");
  EXPECT_NE(e.find("out of range"), std::string::npos);

  e = ErrorOf(kCameras, kImages, "0 1 2 3 1 2 3 0.5 1\n");
  EXPECT_NE(e.find("odd number"), std::string::npos);

  e = ErrorOf(kCameras, kImages, "0 1 2 3 1 2 3\n");
  EXPECT_NE(e.find("truncated"), std::string::npos);

  e = ErrorOf(kCameras, kImages, "0 1 2 3 1 2 3 0.5\n0 1 2 3 1 2 3 0.5\n");
  EXPECT_NE(e.find("points3D.txt:2: duplicate POINT3D_ID 0"), std::string::npos);

  e = ErrorOf(kCameras, kImages, "0 1 nan 3 1 2 3 0.5\n");
  EXPECT_NE(e.find("Y is not finite"), std::string::npos);
}

// A global C++ locale with a decimal comma (as de_DE has) must not change how "0.5"
// parses. The facet is built here because the test machines have no de_DE locale.
struct CommaDecimal : std::numpunct<char> {
  char do_decimal_point() const override { return ','; }
  char do_thousands_sep() const override { return '.'; }
  std::string do_grouping() const override { return "\3"; }
};

TEST(ColmapIoTest, IgnoresGlobalDecimalCommaLocale) {
  const std::locale previous =
      std::locale::global(std::locale(std::locale::classic(), new CommaDecimal));
  const ImageBlock block = ReadStrings(kCameras, kImages, kPoints);
  std::locale::global(previous);
  EXPECT_EQ(block.images[0].cam_from_world.translation.x(), 0.5);
  EXPECT_EQ(block.points[0].error, 0.25);
}

}  // namespace
}  // namespace facets
