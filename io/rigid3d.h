// A rigid transformation. `cam_from_world` maps a point given in (local) object
// coordinates into the camera frame: point_in_cam = rotation * point_in_world +
// translation. This is COLMAP's images.txt convention (QW QX QY QZ TX TY TZ).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace facets {

struct Rigid3d {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Rigid3d() = default;
  Rigid3d(const Eigen::Quaterniond& q, const Eigen::Vector3d& t)
      : rotation(q.normalized()), translation(t) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const {
    return rotation * point + translation;
  }
  Rigid3d Inverse() const {
    const Eigen::Quaterniond inv = rotation.conjugate();
    return Rigid3d(inv, -(inv * translation));
  }
};

}  // namespace facets
