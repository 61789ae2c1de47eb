// Interior orientation: the camera models of COLMAP, used everywhere in Facets.
//
// Pixel convention (stated once, used everywhere): the centre of the top-left pixel
// is at (0.5, 0.5); x grows to the right, y grows downwards. The camera frame is
// COLMAP's: x right, y down, z forward along the optical axis (a point in front of
// the camera has z > 0).
//
// Parameter order is COLMAP's, so cameras.txt lines map one to one:
//   SIMPLE_PINHOLE  f, cx, cy
//   PINHOLE         fx, fy, cx, cy
//   SIMPLE_RADIAL   f, cx, cy, k
//   RADIAL          f, cx, cy, k1, k2
//   OPENCV          fx, fy, cx, cy, k1, k2, p1, p2
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace facets {

enum class CameraModel { kSimplePinhole, kPinhole, kSimpleRadial, kRadial, kOpenCV };

// COLMAP's model name ("SIMPLE_RADIAL", ...). Throws std::invalid_argument for a name
// Facets does not know.
CameraModel CameraModelFromName(const std::string& name);
std::string CameraModelName(CameraModel model);
// Number of parameters of a model.
int CameraModelNumParams(CameraModel model);

struct Camera {
  int camera_id = 0;
  CameraModel model = CameraModel::kPinhole;
  int width = 0;   // pixels
  int height = 0;  // pixels
  std::vector<double> params;
  // Physical pixel pitch in micrometres when known (aerial cameras, project files);
  // 0 when unknown (COLMAP models). Only used to write focal lengths in mm.
  double pixel_size_um = 0.0;

  // A camera of the given model with focal length(s) and principal point set and all
  // distortion coefficients zero.
  static Camera Create(CameraModel model, double fx, double fy, double cx, double cy,
                       int width, int height);

  double FocalX() const;
  double FocalY() const;
  double PrincipalX() const;
  double PrincipalY() const;
  bool HasDistortion() const;

  // Throws std::invalid_argument when the parameter count does not match the model or
  // a value is not finite or the focal length / size is not positive; `what` names
  // the camera.
  void Check() const;

  // Pixel position of a point given in the camera frame (z must be > 0).
  Eigen::Vector2d ImageFromCam(const Eigen::Vector3d& point_in_cam) const;
  // Ray direction (camera frame, z = 1) through a pixel position; lens distortion is
  // removed iteratively (Newton with the analytic Jacobian) to 1e-14 in normalised
  // coordinates.
  Eigen::Vector3d CamFromImage(const Eigen::Vector2d& pixel) const;

  // Normalised image coordinates (x/z, y/z) -> distorted normalised coordinates.
  Eigen::Vector2d Distort(const Eigen::Vector2d& undistorted) const;
  // Inverse of Distort.
  Eigen::Vector2d Undistort(const Eigen::Vector2d& distorted) const;

  // The camera for an image resampled by `factor` (0.5 = half size, one pyramid level
  // up). With the pixel-centre convention above, pixel coordinates scale exactly:
  // focal lengths and principal point multiply by factor, sizes are rounded up.
  Camera Scaled(double factor) const;

  // The same camera with the principal point moved by (dx, dy) pixels. Converts a
  // calibration made with another pixel convention: one that puts the top-left pixel's
  // centre at (0, 0) (e.g. Middlebury's K matrices) needs (+0.5, +0.5) here.
  Camera WithPrincipalPointShifted(double dx, double dy) const;
};

}  // namespace facets
