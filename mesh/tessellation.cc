#include "mesh/tessellation.h"

#include <stdexcept>

namespace facets {

const std::array<Eigen::Vector3d, 3>& SubTriangleCorners(int k) {
  // Built once: lattice node (i, j) with i + j <= n has barycentrics
  // ((n-i-j)/n, i/n, j/n). Upward triangles then downward ones, row by row.
  static const std::array<std::array<Eigen::Vector3d, 3>, kSubTrianglesPerFace> corners = [] {
    std::array<std::array<Eigen::Vector3d, 3>, kSubTrianglesPerFace> out;
    const double n = kSubdivisions;
    auto node = [n](int i, int j) { return Eigen::Vector3d((n - i - j) / n, i / n, j / n); };
    int k = 0;
    for (int j = 0; j < kSubdivisions; ++j) {
      for (int i = 0; i + j < kSubdivisions; ++i) {
        out[k++] = {node(i, j), node(i + 1, j), node(i, j + 1)};
        if (i + j + 1 < kSubdivisions) {
          out[k++] = {node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)};
        }
      }
    }
    return out;
  }();
  if (k < 0 || k >= kSubTrianglesPerFace) throw std::out_of_range("SubTriangleCorners");
  return corners[k];
}

}  // namespace facets
