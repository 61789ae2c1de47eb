#include "io/image_frame.h"

namespace facets {

ImageFrame::ImageFrame(const Camera& camera)
    : camera_(&camera), min_(Eigen::Vector2d::Constant(1e300)), max_(Eigen::Vector2d::Constant(-1e300)) {
  for (int k = 0; k <= 8; ++k) {
    const double a = k / 8.0;
    for (const Eigen::Vector2d& pixel :
         {Eigen::Vector2d(a * camera.width, 0), Eigen::Vector2d(a * camera.width, camera.height),
          Eigen::Vector2d(0, a * camera.height), Eigen::Vector2d(camera.width, a * camera.height)}) {
      const Eigen::Vector2d ray = camera.CamFromImage(pixel).head<2>();
      min_ = min_.cwiseMin(ray);
      max_ = max_.cwiseMax(ray);
    }
  }
  const Eigen::Vector2d margin = 0.01 * (max_ - min_);
  min_ -= margin;
  max_ += margin;
}

bool ImageFrame::Contains(const BlockImage& image, const Eigen::Vector3d& point) const {
  const Eigen::Vector3d in_cam = image.cam_from_world * point;
  if (!(in_cam.z() > 0)) return false;
  const Eigen::Vector2d ray = in_cam.head<2>() / in_cam.z();
  if ((ray.array() < min_.array()).any() || (ray.array() > max_.array()).any()) return false;
  const Eigen::Vector2d pixel = camera_->ImageFromCam(in_cam);
  return pixel.x() >= 0 && pixel.y() >= 0 && pixel.x() <= camera_->width && pixel.y() <= camera_->height;
}

}  // namespace facets
