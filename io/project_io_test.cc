#include "io/project_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "io/colmap_io.h"
#include "io/shared_data_for_testing.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("facets_io_test_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

// Pixel position of a local object point in an image of the block.
Eigen::Vector2d Project(const ImageBlock& block, const BlockImage& image,
                        const Eigen::Vector3d& point_local) {
  return block.CameraOf(image).ImageFromCam(image.cam_from_world * point_local);
}

// An aerial block in the terms of seed 000: f = 153 mm, 20 um pixels, flying height
// 1800 m; angles given in `unit`.
std::string AerialProject(const std::string& unit, double omega, double phi, double kappa) {
  std::ostringstream s;
  s.precision(17);
  s << R"({
  "format": "facets-project", "version": 1, "angle_unit": ")"
    << unit << R"(", "rotation": "omega-phi-kappa",
  "crs": "EPSG:2180",
  "cameras": [{"id": 3, "focal_length_mm": 153.0, "pixel_size_um": 20.0,
               "principal_point_offset_mm": [0.012, -0.021],
               "width_px": 11500, "height_px": 7500}],
  "images": [
    {"id": 1, "path": "img/left.tif", "camera": 3, "projection_centre": [1000, 2000, 1800],
     "omega": )"
    << omega << R"(, "phi": )" << phi << R"(, "kappa": )" << kappa << R"(},
    {"id": 2, "path": "img/right.tif", "camera": 3, "projection_centre": [1432, 2010, 1795],
     "omega": 0, "phi": 0, "kappa": 0}],
  "region_of_interest": {"min": [1000, 1900, 0], "max": [1400, 2100, 100]},
  "mean_terrain_height": 35.5
})";
  return s.str();
}

// The collinearity equations evaluated by hand with explicit rotation matrices:
// R = R_x(omega) R_y(phi) R_z(kappa) maps photo to object coordinates;
// x = x0 - c (r11 dX + r21 dY + r31 dZ) / (r13 dX + r23 dY + r33 dZ), y likewise with
// r12, r22, r32; photo y is up, pixel rows go down.
Eigen::Vector2d CollinearityByHand(double omega, double phi, double kappa,
                                   const Eigen::Vector3d& X0, const Eigen::Vector3d& X) {
  const double co = std::cos(omega), so = std::sin(omega);
  const double cp = std::cos(phi), sp = std::sin(phi);
  const double ck = std::cos(kappa), sk = std::sin(kappa);
  const double Rx[3][3] = {{1, 0, 0}, {0, co, -so}, {0, so, co}};
  const double Ry[3][3] = {{cp, 0, sp}, {0, 1, 0}, {-sp, 0, cp}};
  const double Rz[3][3] = {{ck, -sk, 0}, {sk, ck, 0}, {0, 0, 1}};
  double RxRy[3][3] = {}, R[3][3] = {};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) RxRy[i][j] += Rx[i][k] * Ry[k][j];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) R[i][j] += RxRy[i][k] * Rz[k][j];
  const double dX = X.x() - X0.x(), dY = X.y() - X0.y(), dZ = X.z() - X0.z();
  const double c = 153.0, x0 = 0.012, y0 = -0.021;  // mm
  const double n = R[0][2] * dX + R[1][2] * dY + R[2][2] * dZ;
  const double x_mm = x0 - c * (R[0][0] * dX + R[1][0] * dY + R[2][0] * dZ) / n;
  const double y_mm = y0 - c * (R[0][1] * dX + R[1][1] * dY + R[2][1] * dZ) / n;
  const double pixel_mm = 0.020;
  return {11500 / 2.0 + x_mm / pixel_mm, 7500 / 2.0 - y_mm / pixel_mm};
}

void CheckAgainstCollinearity(const std::string& unit, double unit_per_degree) {
  const double omega = 2, phi = -3, kappa = 30;  // degrees
  const fs::path dir = TempDir("project_opk_" + unit);
  WriteText(dir / "block.json", AerialProject(unit, omega * unit_per_degree,
                                              phi * unit_per_degree, kappa * unit_per_degree));
  const ImageBlock block = ReadProject((dir / "block.json").string());
  // Mean centre (1216, 2005, ...) rounds to whole kilometres, Z = 0.
  EXPECT_EQ(block.origin, Eigen::Vector3d(1000, 2000, 0));
  EXPECT_EQ(block.crs, "EPSG:2180");
  ASSERT_TRUE(block.mean_height.has_value());
  EXPECT_DOUBLE_EQ(*block.mean_height, 35.5);
  ASSERT_TRUE(block.roi.has_value());
  EXPECT_EQ(block.roi->min, Eigen::Vector3d(0, -100, 0));
  EXPECT_EQ(block.images[0].path, (dir / "img/left.tif").string());
  const Camera& camera = block.cameras.at(3);
  EXPECT_DOUBLE_EQ(camera.FocalX(), 7650.0);
  EXPECT_DOUBLE_EQ(camera.PrincipalX(), 5750.0 + 0.6);
  EXPECT_DOUBLE_EQ(camera.PrincipalY(), 3750.0 + 1.05);
  EXPECT_EQ(camera.pixel_size_um, 20.0);
  EXPECT_TRUE(block.images[0].ProjectionCentre().isApprox(Eigen::Vector3d(0, 0, 1800), 1e-14));

  const double rad = std::numbers::pi / 180;
  const Eigen::Vector3d X0(1000, 2000, 1800);
  double max_error = 0;
  int n = 0;
  for (double gx = 700; gx <= 1300; gx += 100) {
    for (double gy = 1600; gy <= 2400; gy += 100) {
      const Eigen::Vector3d X(gx, gy, 30 + 0.01 * gx - 0.02 * gy);
      const Eigen::Vector2d expected = CollinearityByHand(omega * rad, phi * rad, kappa * rad, X0, X);
      const Eigen::Vector2d actual = Project(block, block.images[0], X - block.origin);
      max_error = std::max(max_error, (actual - expected).norm());
      ++n;
    }
  }
  std::cout << unit << ": max |pixel - collinearity by hand| over " << n
            << " ground points = " << max_error << " px\n";
  EXPECT_LT(max_error, 1e-9);
  // A concrete number to quote: the nadir point of the untilted second image lands on
  // the principal point.
  const Eigen::Vector2d nadir =
      Project(block, block.images[1], Eigen::Vector3d(1432, 2010, 0) - block.origin);
  EXPECT_NEAR(nadir.x(), camera.PrincipalX(), 1e-9);
  EXPECT_NEAR(nadir.y(), camera.PrincipalY(), 1e-9);
  fs::remove_all(dir);
}

TEST(ProjectIoTest, OmegaPhiKappaMatchesCollinearityDegrees) {
  CheckAgainstCollinearity("deg", 1.0);
}

TEST(ProjectIoTest, OmegaPhiKappaMatchesCollinearityGon) {
  CheckAgainstCollinearity("gon", 400.0 / 360.0);
}

// Photo x to the right, y up: with all angles zero, a ground point east of the nadir
// appears right of the centre, one north of it above the centre (smaller row).
TEST(ProjectIoTest, PhotoAxesAreRightAndUp) {
  const fs::path dir = TempDir("project_axes");
  WriteText(dir / "p.json", AerialProject("deg", 0, 0, 0));
  const ImageBlock block = ReadProject((dir / "p.json").string());
  const Camera& camera = block.cameras.at(3);
  const Eigen::Vector2d east = Project(block, block.images[0], Eigen::Vector3d(100, 0, 0));
  const Eigen::Vector2d north = Project(block, block.images[0], Eigen::Vector3d(0, 100, 0));
  EXPECT_GT(east.x(), camera.PrincipalX() + 100);
  EXPECT_NEAR(east.y(), camera.PrincipalY(), 1e-9);
  EXPECT_LT(north.y(), camera.PrincipalY() - 100);
  EXPECT_NEAR(north.x(), camera.PrincipalX(), 1e-9);
  fs::remove_all(dir);
}

void ExpectBlocksEqual(const ImageBlock& a, const ImageBlock& b, double tolerance) {
  EXPECT_EQ(a.origin, b.origin);
  EXPECT_EQ(a.crs, b.crs);
  EXPECT_EQ(a.roi.has_value(), b.roi.has_value());
  if (a.roi && b.roi) {
    EXPECT_LT((a.roi->min - b.roi->min).norm(), tolerance);
    EXPECT_LT((a.roi->max - b.roi->max).norm(), tolerance);
  }
  EXPECT_EQ(a.mean_height.has_value(), b.mean_height.has_value());
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (const auto& [id, camera] : a.cameras) {
    const Camera& other = b.cameras.at(id);
    EXPECT_EQ(camera.model, other.model);
    EXPECT_EQ(camera.width, other.width);
    EXPECT_EQ(camera.height, other.height);
    ASSERT_EQ(camera.params.size(), other.params.size());
    for (size_t i = 0; i < camera.params.size(); ++i) {
      EXPECT_NEAR(camera.params[i], other.params[i], tolerance * (1 + std::abs(camera.params[i])));
    }
  }
  ASSERT_EQ(a.images.size(), b.images.size());
  for (size_t i = 0; i < a.images.size(); ++i) {
    EXPECT_EQ(a.images[i].image_id, b.images[i].image_id);
    EXPECT_EQ(a.images[i].camera_id, b.images[i].camera_id);
    EXPECT_EQ(a.images[i].path, b.images[i].path);
    EXPECT_LT(a.images[i].cam_from_world.rotation.angularDistance(b.images[i].cam_from_world.rotation),
              tolerance);
    EXPECT_LT((a.images[i].ProjectionCentre() - b.images[i].ProjectionCentre()).norm(), tolerance);
  }
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].point3d_id, b.points[i].point3d_id);
    EXPECT_LT((a.points[i].xyz - b.points[i].xyz).norm(), tolerance);
    EXPECT_EQ(a.points[i].rgb, b.points[i].rgb);
    EXPECT_EQ(a.points[i].track.size(), b.points[i].track.size());
  }
}

TEST(ProjectIoTest, ReadWriteReadRoundTrip) {
  const fs::path dir = TempDir("project_roundtrip");
  WriteText(dir / "a.json", AerialProject("gon", 2.2, -3.3, 133.3));
  const ImageBlock first = ReadProject((dir / "a.json").string());
  fs::create_directories(dir / "sub");
  WriteProject(first, (dir / "sub" / "b.json").string());
  EXPECT_FALSE(fs::exists(dir / "sub" / "b.json.tmp"));
  const ImageBlock second = ReadProject((dir / "sub" / "b.json").string());
  ExpectBlocksEqual(first, second, 1e-9);
  // Image paths are rewritten relative to the new file and still name the same files.
  EXPECT_EQ(second.images[0].name, "../img/left.tif");
  // A third generation stays within rounding of the first (no drift).
  WriteProject(second, (dir / "sub" / "c.json").string());
  ExpectBlocksEqual(first, ReadProject((dir / "sub" / "c.json").string()), 1e-9);
  fs::remove_all(dir);
}

// A COLMAP block (no pixel size: written with pixel_size_um = 1) through the project
// file: every tie point must project to the same pixel as before.
TEST(ProjectIoTest, ColmapBlockThroughProjectFile) {
  const std::string data = SharedDataDir();
  const char* const models[] = {"boruszyn_kap/sparse_georef_local2180",
                                "strecha_fountain-P11/sparse_with_points"};
  for (const char* sparse : models) FACETS_SKIP_WITHOUT_SHARED_DATA(sparse);
  for (const char* sparse : models) {
    const ImageBlock colmap = ReadColmapModel(data + sparse);
    const fs::path dir = TempDir("project_colmap");
    WriteProject(colmap, (dir / "block.json").string());
    const ImageBlock project = ReadProject((dir / "block.json").string());
    EXPECT_EQ(project.cameras.begin()->second.pixel_size_um, 1.0);
    EXPECT_EQ(project.origin, Eigen::Vector3d::Zero());  // written explicitly
    std::map<int, size_t> index;
    for (size_t i = 0; i < colmap.images.size(); ++i) index[colmap.images[i].image_id] = i;
    double max_error = 0;
    for (size_t p = 0; p < colmap.points.size(); ++p) {
      for (const TrackElement& e : colmap.points[p].track) {
        const size_t i = index.at(e.image_id);
        const Eigen::Vector2d before = Project(colmap, colmap.images[i], colmap.points[p].xyz);
        const Eigen::Vector2d after = Project(project, project.images[i], project.points[p].xyz);
        max_error = std::max(max_error, (before - after).norm());
      }
    }
    std::cout << sparse << " via project file: max tie point pixel change " << max_error
              << " px\n";
    EXPECT_LT(max_error, 1e-8);
    fs::remove_all(dir);
  }
}

std::string ErrorOfProject(const std::string& text) {
  const fs::path dir = TempDir("project_errors");
  WriteText(dir / "bad.json", text);
  try {
    ReadProject((dir / "bad.json").string());
  } catch (const std::runtime_error& e) {
    std::cout << "  error: " << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
    return e.what();
  }
  return "";
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(ProjectIoTest, ErrorsNameFileAndJsonPath) {
  const std::string good = AerialProject("deg", 1, 2, 3);
  EXPECT_EQ(ErrorOfProject(good), "");
  EXPECT_NE(ErrorOfProject(Replace(good, "\"omega\": 0", "\"omega\": \"zero\""))
                .find("images[1].omega is not a number"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"phi\": 0, ", "")).find("images[1].phi is missing"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "[1432, 2010, 1795]", "[1432, 2010]"))
                .find("images[1].projection_centre is not an array of 3 numbers"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"camera\": 3, \"projection_centre\": [1432",
                                   "\"camera\": 4, \"projection_centre\": [1432"))
                .find("images[1].camera refers to unknown camera 4"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"pixel_size_um\": 20.0", "\"pixel_size_um\": -20"))
                .find("cameras[0].pixel_size_um must be positive"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"width_px\": 11500", "\"width_px\": 11500.5"))
                .find("cameras[0].width_px is not an integer"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"focal_length_mm\": 153.0",
                                   "\"model\": \"FISHEYE\", \"focal_length_mm\": 153.0"))
                .find("cameras[0].model camera model 'FISHEYE' is not supported"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"focal_length_mm\": 153.0",
                                   "\"model\": \"RADIAL\", \"distortion\": [0.1], "
                                   "\"focal_length_mm\": 153.0"))
                .find("cameras[0].distortion has 1 coefficients, model RADIAL needs 2"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"angle_unit\": \"deg\"", "\"angle_unit\": \"rad\""))
                .find("angle_unit must be"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "facets-project", "something")).find("format must be"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"version\": 1", "\"version\": 2")).find("version"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"id\": 2,", "\"id\": 1,")).find("duplicates image id 1"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"max\": [1400, 2100, 100]", "\"max\": [1400, 2100, -1]"))
                .find("region_of_interest has min Z > max Z (0.000000 > -1.000000)"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(good.substr(0, good.size() / 2)).find("not valid JSON"),
            std::string::npos);
  EXPECT_THROW(ReadProject("/nonexistent/facets.json"), std::runtime_error);
  // Misspelt keys at every level are errors naming the nearest known key.
  EXPECT_NE(ErrorOfProject(Replace(good, "\"focal_length_mm\": 153.0", "\"focal_lenght_mm\": 153.0"))
                .find("cameras[0]: unknown key 'focal_lenght_mm' (nearest known key: 'focal_length_mm')"),
            std::string::npos);
  EXPECT_NE(ErrorOfProject(Replace(good, "\"crs\"", "\"CRS\"")).find("top level: unknown key 'CRS'"),
            std::string::npos);
  fs::remove_all(TempDir("project_errors"));
}

// The complete example in docs/PROJECT_FILE.md is a valid project file.
TEST(ProjectIoTest, DocumentedExampleReads) {
  std::ifstream doc(std::string(FACETS_SOURCE_DIR) + "/docs/PROJECT_FILE.md");
  ASSERT_TRUE(doc.good());
  std::string line, json;
  bool inside = false, done = false;
  while (!done && std::getline(doc, line)) {
    if (!inside && line == "```json") {
      inside = true;
    } else if (inside && line == "```") {
      done = true;
    } else if (inside) {
      json += line + "\n";
    }
  }
  ASSERT_TRUE(done) << "no ```json block in docs/PROJECT_FILE.md";
  const fs::path dir = TempDir("project_doc");
  WriteText(dir / "example.json", json);
  const ImageBlock block = ReadProject((dir / "example.json").string());
  std::cout << "documented example: " << block.cameras.size() << " cameras, "
            << block.images.size() << " images, origin " << block.origin.transpose() << "\n";
  EXPECT_GE(block.images.size(), 2u);
  EXPECT_TRUE(block.roi.has_value());
  EXPECT_TRUE(block.mean_height.has_value());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace facets
