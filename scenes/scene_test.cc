#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <sstream>
#include <string>

#include "scenes/camera_layout.h"
#include "scenes/scene.h"
#include "scenes/truth_mesh.h"

namespace facets {
namespace {

std::string DataPath(const std::string& name) {
  return std::string(FACETS_SOURCE_DIR) + "/scenes/data/" + name;
}

TEST(SceneTest, BundledScenesLoadAndBuild) {
  const std::pair<const char*, size_t> scenes[] = {
      {"seed_gable_parallel.json", 2},  {"seed_gable_parallel_patch.json", 2},
      {"seed_gable_rotated.json", 2},   {"seed_gable_rotated_patch.json", 2},
      {"seed_cylinder_parallel.json", 2}, {"seed_cylinder_parallel_patch.json", 2},
      {"seed_cylinder_rotated.json", 2}, {"seed_cylinder_rotated_patch.json", 2},
      {"block.json", 13},               {"block_oblique.json", 21},
      {"block_tower.json", 21},         {"block_courtyard.json", 21},
      {"object.json", 20}};
  for (const auto& [file, images] : scenes) {
    const Scene scene = LoadScene(DataPath(file));
    const TruthMesh mesh = BuildTruthMesh(scene);
    const ImageBlock block = BuildImageBlock(scene);
    std::cout << file << ": " << mesh.vertices.size() << " vertices, " << mesh.faces.size()
              << " faces, " << block.images.size() << " images, first "
              << block.CameraOf(block.images[0]).width << "x"
              << block.CameraOf(block.images[0]).height << "\n";
    EXPECT_EQ(block.images.size(), images) << file;
    EXPECT_EQ(mesh.labels.size(), mesh.faces.size());
    for (const auto& [id, camera] : block.cameras) EXPECT_NO_THROW(camera.Check());
  }
}

TEST(SceneTest, ErrorsNameFileAndJsonPath) {
  const std::string text = R"({"name": "t", "ground_pixel_size": 0.1,
    "region_of_interest": {"min": [0,0,0], "max": [1,1,1]},
    "surface": [{"type": "plane"}, {"type": "building", "width": "wide"}],
    "cameras": {"type": "ring", "width": 10, "height": 10, "rings": [{"radius": 1, "elevation_deg": 10, "count": 3}]}})";
  std::istringstream in(text);
  try {
    ParseScene(in, "bad.json");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    std::cout << "message: " << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find("bad.json: /surface/1/width"), std::string::npos);
  }
  std::istringstream unknown(R"({"name": "t", "ground_pixel_size": 0.1,
    "region_of_interest": {"min": [0,0,0], "max": [1,1,1]},
    "surface": [{"type": "torus"}], "cameras": {"type": "stereo"}})");
  EXPECT_THROW(ParseScene(unknown, "u.json"), std::invalid_argument);
  EXPECT_THROW(LoadScene("/nonexistent/scene.json"), std::runtime_error);
  std::istringstream broken("{not json");
  EXPECT_THROW(ParseScene(broken, "broken.json"), std::runtime_error);
}

// Ridge height = half width * tan(20 deg); every roof vertex on its analytic plane.
TEST(TruthMeshTest, GableRoofMatchesAnalyticShape) {
  for (const char* file : {"seed_gable_parallel.json", "seed_gable_rotated.json"}) {
    const Scene scene = LoadScene(DataPath(file));
    const Shape& roof = scene.surface[1];
    const TruthMesh mesh = BuildTruthMesh(scene);
    const double t = std::tan(roof.slope_deg * M_PI / 180);
    const double a = roof.azimuth_deg * M_PI / 180;
    double max_z = -1e9, max_err = 0;
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      if (mesh.labels[f] != kLabelRoof) continue;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d& p = mesh.vertices[mesh.faces[f][k]];
        const double v = -std::sin(a) * p.x() + std::cos(a) * p.y();
        max_err = std::max(max_err, std::abs(p.z() - (0.5 * roof.width - std::abs(v)) * t));
        max_z = std::max(max_z, p.z());
      }
    }
    const double expected = 0.5 * roof.width * std::tan(20 * M_PI / 180);
    std::cout << file << ": ridge height " << max_z << " expected " << expected
              << ", max vertex error " << max_err << "\n";
    EXPECT_NEAR(max_z, expected, 1e-9);
    EXPECT_LT(max_err, 1e-9);
  }
}

TEST(TruthMeshTest, ParabolicCylinderSagittaBelowTolerance) {
  const Scene scene = LoadScene(DataPath("seed_cylinder_rotated.json"));
  const Shape& cyl = scene.surface[1];
  const TruthMesh mesh = BuildTruthMesh(scene);
  const double a = cyl.azimuth_deg * M_PI / 180;
  auto z_of = [&](const Eigen::Vector3d& p) {
    const double v = -std::sin(a) * p.x() + std::cos(a) * p.y();
    const double r = 2 * v / cyl.width;
    return cyl.height * (1 - r * r);
  };
  double vertex_err = 0, sagitta = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.labels[f] != kLabelRoof) continue;
    const auto& F = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      vertex_err = std::max(vertex_err, std::abs(mesh.vertices[F[k]].z() - z_of(mesh.vertices[F[k]])));
    }
    const Eigen::Vector3d c = (mesh.vertices[F[0]] + mesh.vertices[F[1]] + mesh.vertices[F[2]]) / 3;
    sagitta = std::max(sagitta, std::abs(c.z() - z_of(c)));
  }
  std::cout << "cylinder: max vertex error " << vertex_err << " m, max centroid sagitta "
            << sagitta << " m (tolerance " << scene.sagitta_tolerance << ")\n";
  EXPECT_LT(vertex_err, 1e-9);
  EXPECT_LT(sagitta, scene.sagitta_tolerance);
}

TEST(TruthMeshTest, LeaningWallOverhangs) {
  const Scene scene = LoadScene(DataPath("block.json"));
  const Shape& b = scene.surface[3];
  ASSERT_EQ(b.wall_lean_deg[3], 9);
  const TruthMesh mesh = BuildTruthMesh(scene);
  const double ground = *GroundHeightAt(scene, b.centre.x(), b.centre.y());
  // The -Y wall (azimuth 0): its points satisfy y = cy - W/2 - (z - ground) tan(9 deg).
  double min_y_eave = 1e9;
  int wall_faces = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.shape_index[f] != 3 || mesh.labels[f] != kLabelWall) continue;
    ++wall_faces;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = mesh.vertices[mesh.faces[f][k]];
      if (std::abs(p.z() - (ground + b.height)) < 1e-9) min_y_eave = std::min(min_y_eave, p.y());
    }
  }
  const double overhang = b.height * std::tan(9 * M_PI / 180);
  std::cout << "leaning wall: eave at y = " << min_y_eave << ", foot at "
            << b.centre.y() - 0.5 * b.width << ", overhang " << overhang << " m, wall faces "
            << wall_faces << "\n";
  EXPECT_NEAR(min_y_eave, b.centre.y() - 0.5 * b.width - overhang, 1e-9);
  EXPECT_EQ(wall_faces, 8);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.shape_index[f] == 3 && mesh.labels[f] == kLabelWall) {
      const Eigen::Vector3d n = mesh.FaceNormal(static_cast<int>(f));
      const Eigen::Vector3d c = mesh.Point(static_cast<int>(f), 1.0 / 3, 1.0 / 3);
      EXPECT_GT(n.head<2>().dot(c.head<2>() - b.centre.head<2>()), 0) << "normal not outward";
    }
  }
}

TEST(TruthMeshTest, BlockBuildingsHaveRoofsWallsAndHipHeight) {
  const Scene scene = LoadScene(DataPath("block.json"));
  const TruthMesh mesh = BuildTruthMesh(scene);
  int count[4] = {0, 0, 0, 0};
  for (int l : mesh.labels) ++count[l];
  std::cout << "block faces: ground " << count[0] << ", roof " << count[1] << ", wall "
            << count[2] << ", object " << count[3] << "\n";
  EXPECT_GT(count[0], 100000);
  EXPECT_EQ(count[3], 0);
  // Roof triangles: gable 2 planes x 2, hip 2 trapezoids x 2 + 2 triangles, flat 2 x 2,
  // gable 4: 4 + 6 + 2 + 2 + 4 = 18; walls: 5 x 4 x 2 + 2 gables x 2 ends = 44.
  EXPECT_EQ(count[1], 18);
  EXPECT_EQ(count[2], 44);
  const Shape& hip = scene.surface[2];
  const double ground = *GroundHeightAt(scene, hip.centre.x(), hip.centre.y());
  double top = -1e9;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.shape_index[f] != 2) continue;
    for (int k = 0; k < 3; ++k) top = std::max(top, mesh.vertices[mesh.faces[f][k]].z());
  }
  const double expected = ground + hip.height + 0.5 * hip.width * std::tan(30 * M_PI / 180);
  std::cout << "hip ridge at " << top << ", expected " << expected << "\n";
  EXPECT_NEAR(top, expected, 1e-9);
}

TEST(CameraLayoutTest, NadirLookAtAndStereoCrop) {
  const Rigid3d pose = LookAt({10, 20, 100}, {10, 20, 0}, Eigen::Vector3d::UnitY());
  const Eigen::Vector3d right = pose * Eigen::Vector3d(11, 20, 0);
  const Eigen::Vector3d north = pose * Eigen::Vector3d(10, 21, 0);
  EXPECT_GT(right.x(), 0);  // +X to the image right
  EXPECT_LT(north.y(), 0);  // +Y to the image top
  EXPECT_NEAR((pose * Eigen::Vector3d(10, 20, 0)).z(), 100, 1e-12);

  const Scene scene = LoadScene(DataPath("seed_gable_parallel.json"));
  const ImageBlock block = BuildImageBlock(scene);
  const double base = (block.images[1].ProjectionCentre() - block.images[0].ProjectionCentre()).norm();
  std::cout << "stereo base " << base << " m\n";
  EXPECT_NEAR(base, 0.4 * 11500 / 7650.0 * 1800, 1e-6);
  for (const BlockImage& image : block.images) {
    const Camera& camera = block.CameraOf(image);
    std::cout << image.name << ": " << camera.width << "x" << camera.height << " cx "
              << camera.PrincipalX() << " cy " << camera.PrincipalY() << "\n";
    EXPECT_LT(camera.width, 400);
    // The ROI centre projects inside the crop, at least the margin away from the edge.
    const Eigen::Vector2d px = camera.ImageFromCam(image.cam_from_world * Eigen::Vector3d(0, 0, 4));
    EXPECT_GT(px.x(), 50);
    EXPECT_LT(px.x(), camera.width - 50);
    EXPECT_NEAR(camera.FocalX(), 7650, 1e-9);
  }
}

TEST(CameraLayoutTest, ObliqueStripHasParallelAxesSideBySide) {
  // block_oblique.json: 9 nadir, then per direction (N, E, S, W) three obliques 30 m apart.
  const ImageBlock block = BuildImageBlock(LoadScene(DataPath("block_oblique.json")));
  ASSERT_EQ(block.images.size(), 21u);
  const double tilt = 40 * M_PI / 180;
  for (int dir = 0; dir < 4; ++dir) {
    const BlockImage& first = block.images[9 + 3 * dir];
    const Eigen::Vector3d axis0 = first.cam_from_world.rotation.inverse() * Eigen::Vector3d::UnitZ();
    EXPECT_NEAR(std::acos(-axis0.z()), tilt, 1e-9);  // 40 deg off nadir
    for (int k = 1; k < 3; ++k) {
      const BlockImage& other = block.images[9 + 3 * dir + k];
      const Eigen::Vector3d axis =
          other.cam_from_world.rotation.inverse() * Eigen::Vector3d::UnitZ();
      EXPECT_NEAR(axis.dot(axis0), 1.0, 1e-12) << "axes not parallel, direction " << dir;
      const Eigen::Vector3d step = other.ProjectionCentre() - first.ProjectionCentre();
      EXPECT_NEAR(step.norm(), 30.0 * k, 1e-9);
      EXPECT_NEAR(step.dot(axis0), 0.0, 1e-9);  // side by side, across the view
      EXPECT_NEAR(step.z(), 0.0, 1e-9);
    }
  }
}

TEST(CameraLayoutTest, ConvergentObliquesAimAtTheTarget) {
  // block_tower.json: 9 nadir, then per direction three obliques 25 m apart, all aimed at
  // the block centre on the ground: its image is the principal point of each.
  const Scene scene = LoadScene(DataPath("block_tower.json"));
  ASSERT_TRUE(scene.layout.oblique_convergent);
  const ImageBlock block = BuildImageBlock(scene);
  ASSERT_EQ(block.images.size(), 21u);
  const Eigen::Vector3d target(0, 0, 0);
  for (int dir = 0; dir < 4; ++dir) {
    const BlockImage& first = block.images[9 + 3 * dir];
    for (int k = 0; k < 3; ++k) {
      const BlockImage& image = block.images[9 + 3 * dir + k];
      const Camera& camera = block.CameraOf(image);
      const Eigen::Vector2d px = camera.ImageFromCam(image.cam_from_world * target);
      EXPECT_NEAR(px.x(), camera.PrincipalX(), 1e-6) << "direction " << dir << " camera " << k;
      EXPECT_NEAR(px.y(), camera.PrincipalY(), 1e-6) << "direction " << dir << " camera " << k;
      const Eigen::Vector3d step = image.ProjectionCentre() - first.ProjectionCentre();
      EXPECT_NEAR(step.norm(), 25.0 * k, 1e-9);
      EXPECT_NEAR(step.z(), 0.0, 1e-9);
    }
  }
  std::istringstream bad(R"({"name": "b", "ground_pixel_size": 0.1,
    "region_of_interest": {"min": [0, 0, 0], "max": [1, 1, 1]},
    "surface": [{"type": "terrain"}],
    "cameras": {"type": "block", "width": 100, "height": 100, "oblique_axes": "crossed"}})");
  try {
    ParseScene(bad, "bad.json");
    FAIL() << "no error for oblique_axes 'crossed'";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "bad.json: /cameras/oblique_axes: expected 'parallel' or 'convergent'");
  }
}

}  // namespace
}  // namespace facets
