// The plumb prior's observation of one face (AdjustmentOptions::plumb_weight): the z
// component of the face's unit normal, and its gradient with respect to each corner.
#pragma once

#include <Eigen/Core>

namespace facets {

// n = m / |m|, m = (x1 - x0) x (x2 - x0); returns n.z and sets gradient[k] = d n.z / d x_k
// (m = sum over k of x_k x x_(k+1), so dm / dx_k . delta = delta x (x_(k+1) - x_(k+2)) and
// d n.z = (e_z - n n.z) . dm / |m|). A face without area: returns 0, gradients 0.
double FaceNormalZ(const Eigen::Vector3d x[3], Eigen::Vector3d gradient[3]);

}  // namespace facets
