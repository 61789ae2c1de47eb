// The in-memory block of oriented images that every reader produces and every stage
// consumes: cameras (interior orientation), images (exterior orientation and file),
// optional tie points, region of interest and mean terrain height.
//
// All coordinates are local object coordinates in double: a global coordinate is
// `origin + local`. Readers choose the origin (COLMAP models are used as they are,
// origin zero; project files state it or get one near the projection centres) so that
// floats (Embree, glTF) keep millimetres.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/camera.h"
#include "io/rigid3d.h"

namespace facets {

// A 2D feature of an image as in COLMAP's images.txt (pixel convention of camera.h);
// point3d_id is -1 when the feature was not triangulated.
struct Keypoint {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  long long point3d_id = -1;
};

struct BlockImage {
  int image_id = 0;
  std::string name;  // as in the model (relative path)
  std::string path;  // resolved file path ("" until an image folder is known)
  int camera_id = 0;
  Rigid3d cam_from_world;
  // COLMAP's 2D points of this image, kept so a model can be written back unchanged
  // (tie point tracks index into them). Empty for project files.
  std::vector<Keypoint> keypoints;

  // Projection centre X0 in local object coordinates.
  Eigen::Vector3d ProjectionCentre() const {
    return -(cam_from_world.rotation.conjugate() * cam_from_world.translation);
  }
};

struct TrackElement {
  int image_id = 0;
  int point2d_idx = 0;
};

struct TiePoint {
  long long point3d_id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();  // local object coordinates
  Eigen::Vector3i rgb = Eigen::Vector3i::Zero();
  double error = 0.0;  // mean reprojection error, pixels
  std::vector<TrackElement> track;
};

// Axis-aligned region of interest in local object coordinates.
struct RegionOfInterest {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
  bool Contains(const Eigen::Vector3d& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
};

struct ImageBlock {
  std::map<int, Camera> cameras;
  std::vector<BlockImage> images;
  std::vector<TiePoint> points;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // global = origin + local
  std::string crs;                                  // e.g. "EPSG:2180", "" if unknown
  std::optional<RegionOfInterest> roi;
  std::optional<double> mean_height;  // local Z of the mean terrain, if known

  const Camera& CameraOf(const BlockImage& image) const { return cameras.at(image.camera_id); }
};

// Median ground pixel of the block's images at `centre` (m): over the images, the
// distance from the projection centre to `centre` divided by the focal length in pixels
// (the mean of x and y); 0 for a block without images.
inline double GroundPixel(const ImageBlock& block, const Eigen::Vector3d& centre) {
  std::vector<double> gsd;
  for (const auto& image : block.images) {
    const Camera& camera = block.CameraOf(image);
    const double focal = 0.5 * (camera.FocalX() + camera.FocalY());
    gsd.push_back((centre - image.ProjectionCentre()).norm() / focal);
  }
  if (gsd.empty()) return 0.0;
  std::nth_element(gsd.begin(), gsd.begin() + gsd.size() / 2, gsd.end());
  return gsd[gsd.size() / 2];
}

// Moves every camera's principal point by (dx, dy) pixels (Camera::WithPrincipalPointShifted):
// for a calibration made with another pixel convention than Facets' (camera.h).
inline void ShiftPrincipalPoints(ImageBlock& block, double dx, double dy) {
  if (!std::isfinite(dx) || !std::isfinite(dy)) {
    throw std::invalid_argument("principal point shift: both values must be finite numbers");
  }
  for (auto& [id, camera] : block.cameras) camera = camera.WithPrincipalPointShifted(dx, dy);
}

}  // namespace facets
