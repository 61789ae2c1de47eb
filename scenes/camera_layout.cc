#include "scenes/camera_layout.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace facets {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct Pose {
  Eigen::Vector3d centre, target, up;
};

std::string ImageName(int i) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "img_%02d.png", i);
  return buf;
}

// Cuts `camera` to the pixel box of the ROI corners seen from `pose` plus a margin.
Camera CropToRoi(const Camera& full, const Rigid3d& cam_from_world, const RegionOfInterest& roi,
                 int margin, const std::string& scene_name) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d p((k & 1) ? roi.max.x() : roi.min.x(), (k & 2) ? roi.max.y() : roi.min.y(),
                            (k & 4) ? roi.max.z() : roi.min.z());
    const Eigen::Vector3d pc = cam_from_world * p;
    if (pc.z() <= 0) {
      throw std::invalid_argument(scene_name + ": /cameras/crop_to_roi: region of interest "
                                               "is behind a camera");
    }
    const Eigen::Vector2d px = full.ImageFromCam(pc);
    x0 = std::min(x0, px.x());
    y0 = std::min(y0, px.y());
    x1 = std::max(x1, px.x());
    y1 = std::max(y1, px.y());
  }
  const int ix0 = std::max(0, static_cast<int>(std::floor(x0)) - margin);
  const int iy0 = std::max(0, static_cast<int>(std::floor(y0)) - margin);
  const int ix1 = std::min(full.width, static_cast<int>(std::ceil(x1)) + margin);
  const int iy1 = std::min(full.height, static_cast<int>(std::ceil(y1)) + margin);
  if (ix1 <= ix0 || iy1 <= iy0) {
    throw std::invalid_argument(scene_name + ": /cameras/crop_to_roi: region of interest "
                                             "is outside the frame");
  }
  Camera crop = Camera::Create(CameraModel::kPinhole, full.FocalX(), full.FocalY(),
                               full.PrincipalX() - ix0, full.PrincipalY() - iy0, ix1 - ix0,
                               iy1 - iy0);
  crop.pixel_size_um = full.pixel_size_um;
  return crop;
}

// Two nadir images side by side along x, the base set by the overlap; a zero frame
// size becomes the square frame_mm frame.
std::vector<Pose> StereoPoses(const CameraLayout& c, double f_px, int* width, int* height) {
  const int frame_px = static_cast<int>(std::lround(c.frame_mm * 1000.0 / c.pixel_um));
  if (*width == 0) *width = frame_px;
  if (*height == 0) *height = frame_px;
  const double z_fly = c.reference_height + c.flying_height;
  const double base = (1 - c.overlap) * (*width / f_px) * c.flying_height;
  std::vector<Pose> poses;
  for (int side : {-1, 1}) {
    const Eigen::Vector3d centre(c.target.x() + 0.5 * side * base, c.target.y(), z_fly);
    poses.push_back({centre, Eigen::Vector3d(centre.x(), centre.y(), c.reference_height),
                     Eigen::Vector3d::UnitY()});
  }
  return poses;
}

// Nadir rows x cols around the target with the forward and side overlaps, then a strip
// of obliques per direction (north, east, south, west) looking at the target.
std::vector<Pose> BlockPoses(const CameraLayout& c, double f_px, int width, int height) {
  const double z_fly = c.reference_height + c.flying_height;
  const Eigen::Vector3d ground_target(c.target.x(), c.target.y(), c.reference_height);
  std::vector<Pose> poses;
  const double gx = width / f_px * c.flying_height, gy = height / f_px * c.flying_height;
  const double bx = (1 - c.forward_overlap) * gx, by = (1 - c.side_overlap) * gy;
  for (int r = 0; r < c.rows; ++r) {
    for (int k = 0; k < c.cols; ++k) {
      const Eigen::Vector3d centre(c.target.x() + (k - 0.5 * (c.cols - 1)) * bx,
                                   c.target.y() + (r - 0.5 * (c.rows - 1)) * by, z_fly);
      poses.push_back({centre, Eigen::Vector3d(centre.x(), centre.y(), c.reference_height),
                       Eigen::Vector3d::UnitY()});
    }
  }
  const double d = c.flying_height * std::tan(c.oblique_tilt_deg * kDeg);
  // Looking north (from the south), east, south, west.
  const Eigen::Vector2d dirs[4] = {{0, 1}, {1, 0}, {0, -1}, {-1, 0}};
  const double strip_base = c.oblique_base > 0 ? c.oblique_base : bx;
  for (int i = 0; i < c.obliques; ++i) {
    // Across the viewing direction (to the camera's right); parallel axes or all aimed
    // at the target.
    const Eigen::Vector3d across(dirs[i].y(), -dirs[i].x(), 0);
    for (int k = 0; k < c.oblique_strip; ++k) {
      const Eigen::Vector3d shift = (k - 0.5 * (c.oblique_strip - 1)) * strip_base * across;
      const Eigen::Vector3d centre(c.target.x() - d * dirs[i].x(),
                                   c.target.y() - d * dirs[i].y(), z_fly);
      const Eigen::Vector3d target = c.oblique_convergent ? ground_target : ground_target + shift;
      poses.push_back({centre + shift, target, Eigen::Vector3d::UnitZ()});
    }
  }
  return poses;
}

// Cameras on rings around the target, each looking at it.
std::vector<Pose> RingPoses(const CameraLayout& c) {
  std::vector<Pose> poses;
  for (const RingSpec& ring : c.rings) {
    for (int i = 0; i < ring.count; ++i) {
      const double az = (ring.azimuth_offset_deg + 360.0 * i / ring.count) * kDeg;
      const double el = ring.elevation_deg * kDeg;
      const Eigen::Vector3d centre =
          c.target + ring.radius * Eigen::Vector3d(std::cos(el) * std::cos(az),
                                                   std::cos(el) * std::sin(az), std::sin(el));
      poses.push_back({centre, c.target, Eigen::Vector3d::UnitZ()});
    }
  }
  return poses;
}

}  // namespace

Rigid3d LookAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& target,
               const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = (target - centre).normalized();
  Eigen::Vector3d x = z.cross(up);
  if (x.norm() < 1e-9) throw std::invalid_argument("LookAt: up is parallel to the view");
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  return Rigid3d(Eigen::Quaterniond(R), -(R * centre));
}

ImageBlock BuildImageBlock(const Scene& scene) {
  const CameraLayout& c = scene.layout;
  const std::string& src = scene.source_path.empty() ? scene.name : scene.source_path;
  ImageBlock block;
  block.roi = scene.roi;
  block.mean_height = scene.mean_terrain_height;
  const double f_px = c.focal_mm * 1000.0 / c.pixel_um;
  int width = c.width, height = c.height;
  std::vector<Pose> poses;
  switch (c.type) {
    case LayoutType::kStereo:
      poses = StereoPoses(c, f_px, &width, &height);
      break;
    case LayoutType::kBlock:
      poses = BlockPoses(c, f_px, width, height);
      break;
    case LayoutType::kRing:
      poses = RingPoses(c);
      break;
    case LayoutType::kList:
      for (const ExplicitCamera& e : c.cameras) poses.push_back({e.centre, e.target, e.up});
      break;
  }
  Camera base_camera = Camera::Create(CameraModel::kPinhole, f_px, f_px, 0.5 * width,
                                      0.5 * height, width, height);
  base_camera.pixel_size_um = c.pixel_um;
  for (size_t i = 0; i < poses.size(); ++i) {
    BlockImage image;
    image.image_id = static_cast<int>(i) + 1;
    image.name = ImageName(static_cast<int>(i));
    image.cam_from_world = LookAt(poses[i].centre, poses[i].target, poses[i].up);
    if (c.crop_to_roi) {
      Camera cam = CropToRoi(base_camera, image.cam_from_world, scene.roi, c.crop_margin_px, src);
      cam.camera_id = image.image_id;
      block.cameras[cam.camera_id] = cam;
      image.camera_id = cam.camera_id;
    } else {
      base_camera.camera_id = 1;
      block.cameras[1] = base_camera;
      image.camera_id = 1;
    }
    block.images.push_back(image);
  }
  return block;
}

}  // namespace facets
