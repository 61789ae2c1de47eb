#include "scenes/evaluate.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <array>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "io/colmap_io.h"
#include "io/ply_io.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

constexpr double kGsd = 0.15;  // m, written to truth.json

// Adds an axis-aligned box without a bottom (it stands on something): top face
// labelled `top_label`, the four sides `side_label`. Outward normals.
void AddBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int top_label, int side_label,
            MeshData* mesh) {
  const int base = static_cast<int>(mesh->vertices.size());
  for (int k = 0; k < 2; ++k) {
    const double z = k ? hi.z() : lo.z();
    mesh->vertices.push_back({lo.x(), lo.y(), z});
    mesh->vertices.push_back({hi.x(), lo.y(), z});
    mesh->vertices.push_back({hi.x(), hi.y(), z});
    mesh->vertices.push_back({lo.x(), hi.y(), z});
  }
  auto quad = [&](int a, int b, int c, int d, int label) {
    mesh->faces.emplace_back(base + a, base + b, base + c);
    mesh->faces.emplace_back(base + a, base + c, base + d);
    mesh->face_labels.push_back(label);
    mesh->face_labels.push_back(label);
  };
  quad(4, 5, 6, 7, top_label);
  quad(0, 1, 5, 4, side_label);  // y = lo
  quad(1, 2, 6, 5, side_label);  // x = hi
  quad(2, 3, 7, 6, side_label);  // y = hi
  quad(3, 0, 4, 7, side_label);  // x = lo
}

// Ground 30 m x 30 m at z = 0 (label 0), a 6 x 6 x 4 m building (roof 1, walls 2) and
// a 1 m cube (object 3).
MeshData TruthMesh() {
  MeshData mesh;
  mesh.vertices = {{-15, -15, 0}, {15, -15, 0}, {15, 15, 0}, {-15, 15, 0}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  mesh.face_labels = {0, 0};
  AddBox({-3, -3, 0}, {3, 3, 4}, 1, 2, &mesh);
  AddBox({8, -9, 0}, {9, -8, 1}, 3, 3, &mesh);
  return mesh;
}

// A camera at `centre` looking at `target`; COLMAP frame (x right, y down, z forward).
Rigid3d LookAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d up = std::abs(z.z()) > 0.99 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x = z.cross(up).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d world_from_cam;
  world_from_cam << x, y, z;
  const Eigen::Matrix3d cam_from_world = world_from_cam.transpose();
  return Rigid3d(Eigen::Quaterniond(cam_from_world), -(cam_from_world * centre));
}

// Eight oblique cameras on a ring plus one nadir camera.
ImageBlock Cameras() {
  ImageBlock block;
  block.cameras[1] = Camera::Create(CameraModel::kPinhole, 800, 800, 500, 500, 1000, 1000);
  block.cameras[1].camera_id = 1;
  for (int i = 0; i < 9; ++i) {
    BlockImage image;
    image.image_id = i + 1;
    image.camera_id = 1;
    image.name = "img" + std::to_string(i) + ".png";
    Eigen::Vector3d centre(0, 0, 40);
    if (i < 8) {
      const double a = 2 * M_PI * i / 8.0 + 0.1;
      centre = Eigen::Vector3d(28 * std::cos(a), 28 * std::sin(a), 22);
    }
    image.cam_from_world = LookAt(centre, Eigen::Vector3d(0, 0, 1));
    block.images.push_back(image);
  }
  return block;
}

fs::path WriteTruthFolder(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("facets_evaluate_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  WritePly((dir / "truth.ply").string(), TruthMesh());
  WriteColmapModel(Cameras(), (dir / "sparse").string());
  nlohmann::json j;
  j["ground_pixel_size"] = kGsd;
  j["labels"] = {{"0", "ground"}, {"1", "roof"}, {"2", "wall"}, {"3", "object"}};
  std::ofstream((dir / "truth.json").string()) << j.dump(2);
  return dir;
}

double Within(const RegionScore* r, size_t threshold_index) {
  return r->completeness.within.at(threshold_index);
}

class EvaluateTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(WriteTruthFolder("suite"));
    truth_ = new TruthScene(ReadTruthScene(dir_->string()));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete truth_;
  }
  static fs::path* dir_;
  static TruthScene* truth_;
};
fs::path* EvaluateTest::dir_ = nullptr;
TruthScene* EvaluateTest::truth_ = nullptr;

TEST_F(EvaluateTest, TruthFolderIsReadBack) {
  EXPECT_EQ(truth_->ground_pixel_size, kGsd);
  EXPECT_EQ(truth_->block.images.size(), 9u);
  EXPECT_EQ(truth_->mesh.faces.size(), 22u);
  EXPECT_EQ(truth_->labels.at(2), "wall");
  EXPECT_FALSE(truth_->roi.has_value());
}

TEST_F(EvaluateTest, TruthAgainstItselfIsPerfect) {
  const EvaluationReport report = EvaluateFiles(dir_->string(), (*dir_ / "truth.ply").string());
  std::cout << report.Table();
  ASSERT_EQ(report.regions.size(), 5u);  // ground, roof, wall, object, all
  for (const RegionScore& r : report.regions) {
    std::cout << r.name << ": max error " << r.accuracy.max << " m over " << r.accuracy.count
              << " samples, completeness " << r.completeness.count << " samples, <=0.5 GSD "
              << 100 * r.completeness.within[0] << " %\n";
    EXPECT_GT(r.accuracy.count, 100u) << r.name;
    EXPECT_LT(r.accuracy.max, 1e-9) << r.name;
    EXPECT_GT(r.completeness.count, 100u) << r.name;
    for (double w : r.completeness.within) EXPECT_EQ(w, 1.0) << r.name;
  }
  // Ground under the building is hidden from every camera; walls see some < 2 views.
  size_t hidden = 0;
  for (const TruthSample& s : report.truth_samples) {
    if (s.label == 0 && std::abs(s.point.x()) < 2.9 && std::abs(s.point.y()) < 2.9) {
      ++hidden;
      EXPECT_EQ(s.views, 0) << s.point.transpose();
    }
  }
  std::cout << "ground samples under the building (all 0 views): " << hidden << "\n";
  EXPECT_GT(hidden, 1000u);
  const RegionScore* wall = report.Region("wall");
  ASSERT_NE(wall, nullptr);
  EXPECT_EQ(wall->multi_view.count + wall->few_views.count, wall->completeness.count);
  std::cout << "wall samples: " << wall->multi_view.count << " seen by >= 2 images, "
            << wall->few_views.count << " by < 2\n";
  const auto json = nlohmann::json::parse(report.Json());
  EXPECT_EQ(json["regions"].size(), 5u);
  // The truth is a union of pieces (ground grid, building boxes standing in it), so its
  // triangles touch and cross where the pieces meet; the count is reported as found.
  EXPECT_GT(report.mesh_crossings.pairs, 0);
  EXPECT_EQ(json["mesh_crossing_pairs"], report.mesh_crossings.pairs);
}

TEST_F(EvaluateTest, FlatPlaneFailsOnWallsAndPassesOnGround) {
  MeshData plane;
  plane.vertices = {{-15, -15, 0}, {15, -15, 0}, {15, 15, 0}, {-15, 15, 0}};
  plane.faces = {{0, 1, 2}, {0, 2, 3}};
  const EvaluationReport report = Evaluate(*truth_, plane);
  std::cout << report.Table();
  const RegionScore* wall = report.Region("wall");
  const RegionScore* ground = report.Region("ground");
  const RegionScore* roof = report.Region("roof");
  ASSERT_TRUE(wall && ground && roof);
  std::cout << "plane: wall completeness <=1 GSD " << 100 * Within(wall, 1) << " %, ground "
            << 100 * Within(ground, 1) << " %, roof " << 100 * Within(roof, 1) << " %\n";
  EXPECT_LT(Within(wall, 1), 0.20);
  EXPECT_GT(Within(ground, 1), 0.99);
  EXPECT_EQ(Within(roof, 1), 0.0);
  EXPECT_LT(ground->accuracy.median, 1e-9);
  // The plane runs through the ground hidden under the building (6 x 6 m): those
  // samples' closest truth point is seen by no image, so they count as ground < 2 views.
  const double footprint_samples = 36.0 / (report.sample_spacing * report.sample_spacing);
  EXPECT_GE(ground->accuracy_few_views.count, static_cast<size_t>(0.99 * footprint_samples));
  EXPECT_EQ(ground->accuracy_multi_view.count + ground->accuracy_few_views.count,
            ground->accuracy.count);
  EXPECT_EQ(report.mesh_crossings.pairs, 0);
  // A vertical square through the plane: its two triangles cross the plane's two.
  MeshData crossed = plane;
  crossed.vertices.insert(crossed.vertices.end(), {{0, -5, -1}, {0, 5, -1}, {0, 5, 1}, {0, -5, 1}});
  crossed.faces.insert(crossed.faces.end(), {{4, 5, 6}, {4, 6, 7}});
  const EvaluationReport crossed_report = Evaluate(*truth_, crossed);
  EXPECT_GE(crossed_report.mesh_crossings.pairs, 2);
  EXPECT_LE(crossed_report.mesh_crossings.pairs, 4);
  EXPECT_EQ(crossed_report.mesh_crossings.unchecked, 0);
}

// The truth against itself: accuracy samples and truth samples are the same points, so
// the accuracy split by the views of the closest truth point must give the shares that
// completeness counts for the truth samples.
TEST_F(EvaluateTest, AccuracySplitByViewsMatchesTheTruthSamplesViews) {
  const EvaluationReport report = Evaluate(*truth_, truth_->mesh);
  std::map<int, std::array<size_t, 2>> truth_views;  // label -> {>= 2 views, all}
  for (const TruthSample& s : report.truth_samples) {
    truth_views[s.label][0] += s.views >= 2;
    ++truth_views[s.label][1];
  }
  for (const RegionScore& r : report.regions) {
    if (r.label < 0) continue;
    ASSERT_EQ(r.accuracy_multi_view.count + r.accuracy_few_views.count, r.accuracy.count) << r.name;
    ASSERT_GT(r.accuracy.count, 0u) << r.name;
    const double accuracy_share = double(r.accuracy_multi_view.count) / r.accuracy.count;
    const double truth_share = double(truth_views[r.label][0]) / truth_views[r.label][1];
    std::cout << r.name << ": >= 2 views " << 100 * accuracy_share << " % of accuracy samples, "
              << 100 * truth_share << " % of truth samples\n";
    EXPECT_NEAR(accuracy_share, truth_share, 0.005) << r.name;
    EXPECT_LT(r.accuracy_multi_view.max, 1e-9) << r.name;
  }
  // Some of the ground (under the building and behind it) is seen by fewer than two
  // images, so the split is not trivial.
  EXPECT_GT(report.Region("ground")->accuracy_few_views.count, 0u);
  EXPECT_GT(report.Region("ground")->accuracy_multi_view.count, 0u);
}

TEST_F(EvaluateTest, VerticalOffsetIsMeasuredExactly) {
  MeshData shifted = truth_->mesh;
  for (auto& v : shifted.vertices) v.z() += 0.1;
  const EvaluationReport report = Evaluate(*truth_, shifted);
  std::cout << report.Table();
  const RegionScore* ground = report.Region("ground");
  const RegionScore* roof = report.Region("roof");
  ASSERT_TRUE(ground && roof);
  std::cout.precision(12);
  std::cout << "shift 0.1 m: ground median " << ground->accuracy.median << " m, roof median "
            << roof->accuracy.median << " m\n";
  EXPECT_NEAR(ground->accuracy.median, 0.1, 1e-6);
  EXPECT_NEAR(roof->accuracy.median, 0.1, 1e-6);
  // 0.1 m = 0.67 GSD: the ground is complete at 1 GSD, not at 0.5 GSD.
  EXPECT_EQ(Within(ground, 1), 1.0);
  EXPECT_LT(Within(ground, 0), 0.05);
}

TEST_F(EvaluateTest, RegionOfInterestRestrictsBothSides) {
  EvaluationOptions options;
  RegionOfInterest roi;
  roi.min = Eigen::Vector3d(5, -15, -1);
  roi.max = Eigen::Vector3d(15, 15, 10);
  options.roi = roi;
  const EvaluationReport report = Evaluate(*truth_, truth_->mesh, options);
  for (const TruthSample& s : report.truth_samples) ASSERT_TRUE(roi.Contains(s.point));
  EXPECT_EQ(report.Region("roof")->accuracy.count, 0u);
  EXPECT_EQ(report.Region("wall")->completeness.count, 0u);
  EXPECT_GT(report.Region("object")->completeness.count, 100u);
  std::cout << "roi: " << report.num_reconstruction_samples << " reconstruction samples, "
            << report.num_truth_samples << " truth samples\n";
}

TEST(EvaluateFilesTest, MissingFilesAreNamed) {
  const fs::path dir = WriteTruthFolder("missing");
  fs::remove(dir / "truth.json");
  try {
    ReadTruthScene(dir.string());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    std::cout << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find("truth.json"), std::string::npos);
  }
  std::ofstream((dir / "truth.json").string()) << "{\"labels\": {}}";
  try {
    ReadTruthScene(dir.string());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    std::cout << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find("ground_pixel_size"), std::string::npos);
  }
  fs::remove_all(dir);
}

TEST(SampleSurfaceTest, CountFollowsAreaAndSamplesLieOnFaces) {
  const MeshData mesh = TruthMesh();
  std::vector<int> face_of;
  const auto samples = SampleSurface(mesh, 0.1, &face_of);
  const double area = 900 + 36 + 96 + 1 + 4;
  std::cout << "samples " << samples.size() << " for area " << area << " m^2 at 0.1 m\n";
  EXPECT_EQ(samples.size(), static_cast<size_t>(std::floor(area / 0.01 + 1e-9)));
  std::vector<size_t> per_face(mesh.faces.size(), 0);
  double max_off_plane = 0, max_outside = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const int f = face_of[i];
    ++per_face[f];
    const Eigen::Vector3d a = mesh.vertices[mesh.faces[f][0]];
    const Eigen::Vector3d b = mesh.vertices[mesh.faces[f][1]];
    const Eigen::Vector3d c = mesh.vertices[mesh.faces[f][2]];
    const Eigen::Vector3d n = (b - a).cross(c - a);
    max_off_plane = std::max(max_off_plane, std::abs((samples[i] - a).dot(n.normalized())));
    // Barycentric coordinates from sub-triangle areas: all >= 0 inside the face.
    const double w0 = (b - samples[i]).cross(c - samples[i]).dot(n) / n.squaredNorm();
    const double w1 = (c - samples[i]).cross(a - samples[i]).dot(n) / n.squaredNorm();
    max_outside = std::max({max_outside, -w0, -w1, w0 + w1 - 1.0});
  }
  std::cout << "max distance off the face plane " << max_off_plane
            << " m, max barycentric overshoot " << max_outside << "\n";
  EXPECT_LT(max_off_plane, 1e-12);
  EXPECT_LT(max_outside, 1e-12);
  std::vector<bool> only_ground(mesh.faces.size(), false);
  only_ground[0] = only_ground[1] = true;
  EXPECT_EQ(SampleSurface(mesh, 0.1, nullptr, &only_ground).size(), 90000u);
  // Each ground triangle holds 450 m^2: 45000 samples, +-1 for the running floor.
  EXPECT_NEAR(static_cast<double>(per_face[0]), 45000, 1);
  EXPECT_EQ(SampleSurface(mesh, 0.1), samples);  // deterministic
}

TEST(FitPlaneTest, RecoversKnownTilt) {
  for (double lean_deg : {0.0, 0.7, 3.0, 12.0}) {
    const double lean = lean_deg * M_PI / 180.0;
    // A wall along Y leaning by `lean` towards +X: normal (cos, 0, sin) tilted.
    const Eigen::Vector3d normal(std::cos(lean), 0, -std::sin(lean));
    const Eigen::Vector3d along(0, 1, 0);
    const Eigen::Vector3d up = normal.cross(along).normalized();
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < 20; ++i) {
      for (int k = 0; k < 10; ++k) {
        const double noise = ((i * 7 + k * 3) % 5 - 2) * 0.002;  // +-4 mm, mean 0
        points.push_back(Eigen::Vector3d(100, 50, 10) + 0.5 * i * along + 0.4 * k * up +
                         noise * normal);
      }
    }
    const PlaneFit fit = FitPlane(points);
    std::cout << "lean " << lean_deg << " deg: fitted " << fit.tilt_from_vertical_deg
              << " deg, rms " << fit.rms << " m\n";
    EXPECT_NEAR(fit.tilt_from_vertical_deg, lean_deg, 0.02);
    EXPECT_NEAR(fit.slope_deg, 90 - lean_deg, 0.02);
    EXPECT_LT(fit.rms, 0.004);
  }
  EXPECT_THROW(FitPlane({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}), std::invalid_argument);
}


// Issue 7: the block scene's tall building leans its -v wall 9 degrees outward. Points
// sampled densely on the truth itself must give that lean back, and no other wall is
// reported.
TEST(LeaningWallsTest, BlockSceneTruthGivesItsOwnLean) {
  const Scene scene = LoadScene(std::string(FACETS_SOURCE_DIR) + "/scenes/data/block.json");
  const struct facets::TruthMesh mesh = BuildTruthMesh(scene);
  TruthScene truth;
  truth.mesh.vertices = mesh.vertices;
  truth.mesh.faces = mesh.faces;
  truth.mesh.face_labels = mesh.labels;
  truth.ground_pixel_size = scene.ground_pixel_size;
  for (const Shape& shape : scene.surface) {
    if (shape.type != ShapeType::kBuilding) continue;
    TruthBuilding b;
    b.centre = shape.centre;
    b.azimuth_deg = shape.azimuth_deg;
    b.length = shape.length;
    b.width = shape.width;
    b.height = shape.height;
    b.wall_lean_deg = shape.wall_lean_deg;
    truth.buildings.push_back(b);
  }
  MeshData points;
  points.vertices = SampleSurface(truth.mesh, 0.1);
  const std::vector<WallLean> walls = EvaluateLeaningWalls(truth, points, scene.roi, 8 * scene.ground_pixel_size);
  ASSERT_EQ(walls.size(), 1u);
  std::cout << "leaning wall: true " << walls[0].true_lean_deg << " deg, truth fit "
            << walls[0].truth_fit_lean_deg << ", sampled truth " << walls[0].lean_deg << " deg from "
            << walls[0].vertices << " points, rms " << walls[0].rms << " m\n";
  EXPECT_EQ(walls[0].wall, 3);
  EXPECT_NEAR(walls[0].truth_fit_lean_deg, 9.0, 1e-6);
  EXPECT_NEAR(walls[0].lean_deg, 9.0, 0.05);
  EXPECT_GT(walls[0].vertices, 1000);
}

}  // namespace
}  // namespace facets
