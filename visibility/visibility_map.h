// Per-image visibility maps: for each pixel the sub-triangle (grey facet) its ray sees
// first, or -1, and the distance along the ray. Used for orthophoto, texture and
// "seen by N images" counts.
#pragma once

#include <cstdint>
#include <vector>

#include "visibility/pixel_cast.h"

namespace facets {

struct VisibilityMap {
  int width = 0, height = 0;
  // Row-major, width * height. facet = -1 where the pixel is no observation (miss,
  // back face, grazing); face = facet / 16.
  std::vector<int32_t> facet;
  std::vector<float> distance;  // along the unit ray; +inf where facet == -1

  int Facet(int x, int y) const { return facet[static_cast<size_t>(y) * width + x]; }
  int Face(int x, int y) const {
    const int s = Facet(x, y);
    return s < 0 ? -1 : s / kSubTrianglesPerFace;
  }
  // Pixels per geometry face (size num_faces).
  std::vector<int> PixelsPerFace(int num_faces) const;
  // Pixels per sub-triangle (size num_facets).
  std::vector<int> PixelsPerFacet(int num_facets) const;
};

// Casts every pixel of the image (options.keep_invalid is ignored).
VisibilityMap BuildVisibilityMap(const SurfaceScene& scene, const Camera& camera,
                                 const Rigid3d& cam_from_world,
                                 const CastOptions& options = {});

// For each geometry face: the number of maps in which at least min_pixels pixels see it.
std::vector<int> CountImagesPerFace(const std::vector<VisibilityMap>& maps, int num_faces,
                                    int min_pixels = 1);
// For each geometry vertex (faces = #F by 3 vertex ids, num_vertices = #V): the number
// of maps that see at least one adjacent face (with min_pixels pixels).
std::vector<int> CountImagesPerVertex(const std::vector<VisibilityMap>& maps,
                                      const std::vector<Eigen::Vector3i>& faces,
                                      int num_vertices, int min_pixels = 1);
// For each grey node (tessellation point): the number of maps that see at least one
// grey facet containing it (with min_pixels pixels on that facet).
std::vector<int> CountImagesPerNode(const std::vector<VisibilityMap>& maps,
                                    const Tessellation& tessellation, int min_pixels = 1);

}  // namespace facets
