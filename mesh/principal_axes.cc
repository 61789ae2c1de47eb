#include "mesh/principal_axes.h"

#include <Eigen/Eigenvalues>
#include <stdexcept>

namespace facets {

PrincipalAxes FitPrincipalAxes(const std::vector<Eigen::Vector3d>& points) {
  if (points.empty()) throw std::invalid_argument("principal axes of no points");
  PrincipalAxes fit;
  for (const auto& p : points) fit.centre += p;
  fit.centre /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : points) scatter += (p - fit.centre) * (p - fit.centre).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
  fit.eigenvalues = solver.eigenvalues();
  fit.axes = solver.eigenvectors();
  return fit;
}

}  // namespace facets
