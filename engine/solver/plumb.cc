#include "engine/solver/plumb.h"

#include <Eigen/Geometry>

namespace facets {

double FaceNormalZ(const Eigen::Vector3d x[3], Eigen::Vector3d gradient[3]) {
  const Eigen::Vector3d m = (x[1] - x[0]).cross(x[2] - x[0]);
  const double length = m.norm();
  if (!(length > 0.0)) {
    for (int k = 0; k < 3; ++k) gradient[k].setZero();
    return 0.0;
  }
  const Eigen::Vector3d n = m / length;
  const Eigen::Vector3d tangent = Eigen::Vector3d::UnitZ() - n * n.z();
  for (int k = 0; k < 3; ++k) gradient[k] = (x[(k + 1) % 3] - x[(k + 2) % 3]).cross(tangent) / length;
  return n.z();
}

}  // namespace facets
