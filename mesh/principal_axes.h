// Principal axes of a set of points: the centroid and the eigen decomposition of their
// scatter matrix, sum (p - c)(p - c)^T. The axis of the smallest eigenvalue is the
// normal of the total-least-squares plane, the one of the largest the direction of the
// least-squares line. One implementation for the fits of walls (mesh/unseen_lips.cc),
// crease lines and roof sides (mesh/creases.cc), the fitted start plane
// (engine/start_fitted_plane.cc) and the evaluation's planes (scenes/evaluate.cc).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace facets {

struct PrincipalAxes {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  // Ascending: the sums of the squared distances from the centre along each axis.
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns: unit axes, ascending as the eigenvalues
  Eigen::Vector3d Normal() const { return axes.col(0); }     // of the plane
  Eigen::Vector3d Direction() const { return axes.col(2); }  // of the line
};

// Throws std::invalid_argument for an empty set.
PrincipalAxes FitPrincipalAxes(const std::vector<Eigen::Vector3d>& points);

}  // namespace facets
