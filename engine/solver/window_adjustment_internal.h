// Layout of a window's unknowns shared by the files of WindowAdjustment
// (window_adjustment.cc, window_casting.cc, window_normal_equations.cc,
// window_precision.cc); not part of the solver's interface.
#pragma once

#include <array>
#include <chrono>
#include <cmath>

#include "mesh/tessellation.h"

namespace facets::window_internal {

// Grey-value lattice nodes of one geometry face (kSubdivisions = 4: 5 + 4 + 3 + 2 + 1).
constexpr int kNodesPerFace = 15;
constexpr int kLocal = 3 + kNodesPerFace;  // face-local unknowns per channel

inline double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Face-local id of lattice node (i, j), i + j <= 4, counted row by row.
inline int LocalNodeId(int i, int j) { return 5 * j - j * (j - 1) / 2 + i; }

// For each local sub-triangle k, the face-local node ids of its three corners.
inline const std::array<std::array<int, 3>, kSubTrianglesPerFace>& FacetLocalNodes() {
  static const auto table = [] {
    std::array<std::array<int, 3>, kSubTrianglesPerFace> t;
    for (int k = 0; k < kSubTrianglesPerFace; ++k) {
      const auto& corners = SubTriangleCorners(k);
      for (int c = 0; c < 3; ++c) {
        const int i = static_cast<int>(std::lround(corners[c][1] * kSubdivisions));
        const int j = static_cast<int>(std::lround(corners[c][2] * kSubdivisions));
        t[k][c] = LocalNodeId(i, j);
      }
    }
    return t;
  }();
  return table;
}

}  // namespace facets::window_internal
