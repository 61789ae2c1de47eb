// Test helper: a start surface below the true one, for end-to-end tests that start the
// adjustment from a known offset instead of the pipeline's start plane.
#pragma once

#include "mesh/tin.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"

namespace facets {

// Height of the highest true surface point at (x, y).
inline double TruthHeight(const Renderer& renderer, double x, double y) {
  return renderer.Cast(Eigen::Vector3d(x, y, 1000.0), Eigen::Vector3d(0, 0, -1)).point.z();
}

// Regular grid over the scene's region of interest, `shift` below the truth.
inline TinMesh StartBelowTruth(const Scene& scene, const Renderer& renderer, double spacing,
                               double shift) {
  StartGridOptions grid;
  grid.min = scene.roi.min.head<2>();
  grid.max = scene.roi.max.head<2>();
  grid.spacing = spacing;
  grid.height = [&](double x, double y) { return TruthHeight(renderer, x, y) - shift; };
  return MakeStartGrid(grid);
}

}  // namespace facets
