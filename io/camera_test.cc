#include "io/camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <stdexcept>

namespace facets {
namespace {

struct NamedCamera {
  const char* label;
  Camera camera;
};

// Realistic cameras for every model: the Boruszyn kite camera (SIMPLE_RADIAL as COLMAP
// estimated it), the Strecha focal lengths, and an OPENCV lens with tangential terms.
std::vector<NamedCamera> RealisticCameras() {
  std::vector<NamedCamera> cameras;
  cameras.push_back({"SIMPLE_PINHOLE", Camera::Create(CameraModel::kSimplePinhole, 1520.4,
                                                      1520.4, 302.32, 246.87, 640, 480)});
  cameras.push_back({"PINHOLE", Camera::Create(CameraModel::kPinhole, 2759.48, 2764.16, 1520.69,
                                               1006.81, 3072, 2048)});
  Camera simple_radial = Camera::Create(CameraModel::kSimpleRadial, 942.86985899807928,
                                        942.86985899807928, 576, 432, 1152, 864);
  simple_radial.params[3] = -0.038744509714348535;
  cameras.push_back({"SIMPLE_RADIAL (Boruszyn)", simple_radial});
  Camera radial = Camera::Create(CameraModel::kRadial, 942.87, 942.87, 570.3, 437.9, 1152, 864);
  radial.params[3] = -0.06;
  radial.params[4] = 0.015;
  cameras.push_back({"RADIAL", radial});
  Camera opencv = Camera::Create(CameraModel::kOpenCV, 2759.48, 2764.16, 1520.69, 1006.81,
                                 3072, 2048);
  opencv.params[4] = -0.1;
  opencv.params[5] = 0.02;
  opencv.params[6] = 1e-3;
  opencv.params[7] = -5e-4;
  cameras.push_back({"OPENCV", opencv});
  return cameras;
}

// Pixel -> ray -> pixel over a 41 x 41 grid that includes the outer pixel corners
// (0, 0) and (width, height), at several depths.
TEST(CameraTest, ProjectBackProjectRoundTripEveryModel) {
  for (const auto& [label, camera] : RealisticCameras()) {
    camera.Check();
    double max_error_px = 0;
    double max_ray_error = 0;
    const int n = 40;
    for (int iy = 0; iy <= n; ++iy) {
      for (int ix = 0; ix <= n; ++ix) {
        const Eigen::Vector2d pixel(camera.width * ix / double(n), camera.height * iy / double(n));
        const Eigen::Vector3d ray = camera.CamFromImage(pixel);
        ASSERT_DOUBLE_EQ(ray.z(), 1.0);
        for (double depth : {0.5, 7.0, 1800.0}) {
          const Eigen::Vector2d back = camera.ImageFromCam(ray * depth);
          max_error_px = std::max(max_error_px, (back - pixel).norm());
        }
        // The other direction: a ray -> pixel -> ray.
        const Eigen::Vector3d again = camera.CamFromImage(camera.ImageFromCam(ray));
        max_ray_error = std::max(max_ray_error, (again - ray).norm());
      }
    }
    std::cout << label << ": max pixel round-trip error " << max_error_px
              << " px, max ray error " << max_ray_error << "\n";
    RecordProperty(std::string(label) + "_max_error_px", std::to_string(max_error_px));
    EXPECT_LT(max_error_px, 1e-9) << label;
    EXPECT_LT(max_ray_error, 1e-12) << label;
  }
}

// The distortion really acts: at the corner the distorted and undistorted positions
// differ by many pixels, so the round trip above is not trivially exact.
TEST(CameraTest, DistortionIsSignificantAtCorners) {
  for (const auto& [label, camera] : RealisticCameras()) {
    if (!camera.HasDistortion()) continue;
    const Eigen::Vector2d corner(0, 0);
    const Eigen::Vector3d ray = camera.CamFromImage(corner);
    const Eigen::Vector2d pinhole(camera.FocalX() * ray.x() + camera.PrincipalX(),
                                  camera.FocalY() * ray.y() + camera.PrincipalY());
    const double shift = (pinhole - corner).norm();
    std::cout << label << ": distortion at corner " << shift << " px\n";
    EXPECT_GT(shift, 5.0) << label;
  }
}

// Scaled(0.5) is one pyramid level: with the pixel-centre convention the same object
// point must land at exactly half the pixel coordinates.
TEST(CameraTest, ScaledHalfKeepsProjectionsConsistent) {
  for (const auto& [label, camera] : RealisticCameras()) {
    const Camera half = camera.Scaled(0.5);
    EXPECT_EQ(half.width, (camera.width + 1) / 2);
    EXPECT_EQ(half.height, (camera.height + 1) / 2);
    double max_error = 0;
    for (double x = -0.6; x <= 0.6; x += 0.1) {
      for (double y = -0.4; y <= 0.4; y += 0.1) {
        const Eigen::Vector3d point(x * 10, y * 10, 10.0);
        const Eigen::Vector2d full = camera.ImageFromCam(point);
        const Eigen::Vector2d reduced = half.ImageFromCam(point);
        max_error = std::max(max_error, (reduced - full / 2).norm());
      }
    }
    std::cout << label << ": Scaled(0.5) max |x_half - x_full/2| = " << max_error << " px\n";
    EXPECT_LT(max_error, 1e-12) << label;
  }
  // Odd sizes round up (a 2x2 block reduction keeps the last, partial pixel).
  const Camera odd = Camera::Create(CameraModel::kPinhole, 100, 100, 50, 40, 101, 81);
  EXPECT_EQ(odd.Scaled(0.5).width, 51);
  EXPECT_EQ(odd.Scaled(0.5).height, 41);
}

// A principal-point shift moves every projection by exactly the shift, distortion or
// not (distortion acts on normalised coordinates, before the principal point).
TEST(CameraTest, PrincipalPointShiftMovesEveryProjectionByTheShift) {
  for (const auto& [label, camera] : RealisticCameras()) {
    const Camera shifted = camera.WithPrincipalPointShifted(0.5, -0.25);
    EXPECT_DOUBLE_EQ(shifted.PrincipalX(), camera.PrincipalX() + 0.5) << label;
    EXPECT_DOUBLE_EQ(shifted.PrincipalY(), camera.PrincipalY() - 0.25) << label;
    EXPECT_EQ(shifted.FocalX(), camera.FocalX()) << label;
    double max_error = 0;
    for (double x = -0.6; x <= 0.6; x += 0.1) {
      for (double y = -0.4; y <= 0.4; y += 0.1) {
        const Eigen::Vector3d point(x * 10, y * 10, 10.0);
        const Eigen::Vector2d moved = shifted.ImageFromCam(point) - camera.ImageFromCam(point);
        max_error = std::max(max_error, (moved - Eigen::Vector2d(0.5, -0.25)).norm());
      }
    }
    EXPECT_LT(max_error, 1e-9) << label;
  }
}

TEST(CameraTest, ModelNamesAndParameterCounts) {
  EXPECT_EQ(CameraModelFromName("SIMPLE_PINHOLE"), CameraModel::kSimplePinhole);
  EXPECT_EQ(CameraModelFromName("OPENCV"), CameraModel::kOpenCV);
  EXPECT_EQ(CameraModelNumParams(CameraModel::kSimpleRadial), 4);
  EXPECT_EQ(CameraModelNumParams(CameraModel::kOpenCV), 8);
  EXPECT_EQ(CameraModelName(CameraModel::kRadial), "RADIAL");
  EXPECT_THROW(CameraModelFromName("FULL_OPENCV"), std::invalid_argument);
  EXPECT_THROW(CameraModelFromName("pinhole"), std::invalid_argument);
  try {
    CameraModelFromName("FISHEYE");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("FISHEYE"), std::string::npos) << e.what();
  }
}

TEST(CameraTest, CheckRejectsBadCameras) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Camera camera = RealisticCameras()[4].camera;
  camera.camera_id = 7;
  EXPECT_NO_THROW(camera.Check());

  Camera bad = camera;
  bad.params[0] = nan;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = camera;
  bad.params[6] = nan;  // a distortion coefficient
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = camera;
  bad.params[2] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = camera;
  bad.params.pop_back();
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = camera;
  bad.params[0] = -1;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  bad = camera;
  bad.width = 0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  try {
    Camera named = camera;
    named.params[1] = nan;
    named.Check();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("camera 7"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace facets
