// The truth surface of a scene as one triangle mesh with a region label per face.
//
// Every analytic shape is meshed on its own (shapes may intersect: the terrain runs on
// under buildings, hidden). Flat shapes (planes, roof planes, walls) are exact; curved
// shapes (terrain, parabolic cylinder, blob) use an edge length chosen so that the
// sagitta stays below Scene::sagitta_tolerance (default 1 mm) unless a shape sets
// `step`. Vertices are not shared between differently oriented planes, so every flat
// face carries its plane normal.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "io/ply_io.h"
#include "scenes/scene.h"

namespace facets {

struct TruthMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;     // counter-clockwise seen from outside / above
  std::vector<Eigen::Vector3d> normals;   // per vertex, unit, outward (exact where cheap)
  std::vector<int> labels;                // per face, RegionLabel
  std::vector<unsigned char> smooth;      // per face: 1 = interpolate vertex normals
  std::vector<int> shape_index;           // per face: index into Scene::surface

  // Unit shading normal at barycentric (u, v) of face f (Embree's convention:
  // point = (1-u-v) V0 + u V1 + v V2).
  Eigen::Vector3d ShadingNormal(int face, double u, double v) const;
  Eigen::Vector3d FaceNormal(int face) const;  // unit geometric normal
  Eigen::Vector3d Point(int face, double u, double v) const;
  MeshData ToMeshData() const;
};

// Z of the first terrain (or plane) shape of the scene at (x, y), if one covers it.
std::optional<double> GroundHeightAt(const Scene& scene, double x, double y);

// Throws std::runtime_error (mesh file problems) naming the file.
TruthMesh BuildTruthMesh(const Scene& scene);

}  // namespace facets
