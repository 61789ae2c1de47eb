#include "visibility/visibility_map.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace facets {

std::vector<int> VisibilityMap::PixelsPerFace(int num_faces) const {
  std::vector<int> count(num_faces, 0);
  for (const int32_t s : facet) {
    if (s < 0) continue;
    const int f = s / kSubTrianglesPerFace;
    if (f >= num_faces) throw std::out_of_range("VisibilityMap: face index out of range");
    ++count[f];
  }
  return count;
}

std::vector<int> VisibilityMap::PixelsPerFacet(int num_facets) const {
  std::vector<int> count(num_facets, 0);
  for (const int32_t s : facet) {
    if (s < 0) continue;
    if (s >= num_facets) throw std::out_of_range("VisibilityMap: facet index out of range");
    ++count[s];
  }
  return count;
}

VisibilityMap BuildVisibilityMap(const SurfaceScene& scene, const Camera& camera,
                                 const Rigid3d& cam_from_world, const CastOptions& options) {
  CastOptions valid_only = options;
  valid_only.keep_invalid = false;
  const CastResult cast =
      CastPixels(scene, camera, cam_from_world, PixelRect::Full(camera), valid_only);
  VisibilityMap map;
  map.width = camera.width;
  map.height = camera.height;
  const size_t size = static_cast<size_t>(camera.width) * camera.height;
  map.facet.assign(size, -1);
  map.distance.assign(size, std::numeric_limits<float>::infinity());
  for (const PixelObservation& obs : cast.observations) {
    const size_t i = static_cast<size_t>(obs.y) * camera.width + obs.x;
    map.facet[i] = obs.facet;
    map.distance[i] = obs.distance;
  }
  return map;
}

std::vector<int> CountImagesPerFace(const std::vector<VisibilityMap>& maps, int num_faces,
                                    int min_pixels) {
  std::vector<int> images(num_faces, 0);
  for (const VisibilityMap& map : maps) {
    const std::vector<int> pixels = map.PixelsPerFace(num_faces);
    for (int f = 0; f < num_faces; ++f) images[f] += pixels[f] >= min_pixels;
  }
  return images;
}

std::vector<int> CountImagesPerVertex(const std::vector<VisibilityMap>& maps,
                                      const std::vector<Eigen::Vector3i>& faces,
                                      int num_vertices, int min_pixels) {
  const int num_faces = static_cast<int>(faces.size());
  std::vector<int> images(num_vertices, 0);
  std::vector<char> seen(num_vertices);
  for (const VisibilityMap& map : maps) {
    const std::vector<int> pixels = map.PixelsPerFace(num_faces);
    std::fill(seen.begin(), seen.end(), 0);
    for (int f = 0; f < num_faces; ++f) {
      if (pixels[f] < min_pixels) continue;
      for (int k = 0; k < 3; ++k) {
        if (faces[f][k] < 0 || faces[f][k] >= num_vertices) {
          throw std::out_of_range("CountImagesPerVertex: face " + std::to_string(f) +
                                  " has a vertex index out of range");
        }
        seen[faces[f][k]] = 1;
      }
    }
    for (int v = 0; v < num_vertices; ++v) images[v] += seen[v];
  }
  return images;
}

std::vector<int> CountImagesPerNode(const std::vector<VisibilityMap>& maps,
                                    const Tessellation& tessellation, int min_pixels) {
  const int num_facets = static_cast<int>(tessellation.triangles.size());
  const int num_nodes = static_cast<int>(tessellation.points.size());
  std::vector<int> images(num_nodes, 0);
  std::vector<char> seen(num_nodes);
  for (const VisibilityMap& map : maps) {
    const std::vector<int> pixels = map.PixelsPerFacet(num_facets);
    std::fill(seen.begin(), seen.end(), 0);
    for (int s = 0; s < num_facets; ++s) {
      if (pixels[s] < min_pixels) continue;
      for (int k = 0; k < 3; ++k) seen[tessellation.triangles[s][k]] = 1;
    }
    for (int n = 0; n < num_nodes; ++n) images[n] += seen[n];
  }
  return images;
}

}  // namespace facets
