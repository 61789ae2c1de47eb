#include "visibility/test_util.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

namespace facets {

Rigid3d LookAtForTesting(const Eigen::Vector3d& centre, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d up = std::abs(z.z()) > 0.99 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x = z.cross(up).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d world_from_cam;
  world_from_cam << x, y, z;
  const Eigen::Matrix3d cam_from_world = world_from_cam.transpose();
  return Rigid3d(Eigen::Quaterniond(cam_from_world), -(cam_from_world * centre));
}

void AppendBoxForTesting(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                         bool with_bottom, FlatMesh* mesh) {
  const int base = static_cast<int>(mesh->vertices.size());
  for (int k = 0; k < 8; ++k) {
    mesh->vertices.emplace_back((k & 1) ? max.x() : min.x(), (k & 2) ? max.y() : min.y(),
                                (k & 4) ? max.z() : min.z());
  }
  // Quads (a, b, c, d) counter-clockwise seen from outside.
  const int quads[6][4] = {{4, 5, 7, 6},   // top (+z)
                           {0, 1, 5, 4},   // front (-y)
                           {1, 3, 7, 5},   // right (+x)
                           {3, 2, 6, 7},   // back (+y)
                           {2, 0, 4, 6},   // left (-x)
                           {0, 2, 3, 1}};  // bottom (-z)
  for (int q = 0; q < (with_bottom ? 6 : 5); ++q) {
    const int* v = quads[q];
    mesh->faces.emplace_back(base + v[0], base + v[1], base + v[2]);
    mesh->faces.emplace_back(base + v[0], base + v[2], base + v[3]);
  }
}

Tessellation TessellateFlatForTesting(const FlatMesh& mesh) {
  constexpr int n = kSubdivisions;
  Tessellation tess;
  // Node identity: a mesh vertex, a point on an undirected edge (lower vertex id,
  // higher vertex id, steps from the lower one), or a face-interior lattice node.
  std::map<std::array<int, 4>, int> node_ids;
  const int num_vertices = static_cast<int>(mesh.vertices.size());
  for (int f = 0; f < static_cast<int>(mesh.faces.size()); ++f) {
    const Eigen::Vector3i& face = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      if (face[k] < 0 || face[k] >= num_vertices) {
        throw std::invalid_argument("TessellateFlatForTesting: bad vertex index");
      }
    }
    // Lattice node (i, j): barycentrics ((n-i-j)/n, i/n, j/n) -> counts (c0, c1, c2).
    auto node = [&](const Eigen::Vector3d& bary) {
      std::array<int, 3> c;
      for (int k = 0; k < 3; ++k) c[k] = static_cast<int>(std::lround(bary[k] * n));
      std::array<int, 4> key;
      int nonzero = 0;
      for (int k = 0; k < 3; ++k) nonzero += c[k] != 0;
      if (nonzero == 1) {
        const int k = c[0] ? 0 : (c[1] ? 1 : 2);
        key = {0, face[k], 0, 0};
      } else if (nonzero == 2) {
        const int a = c[0] == 0 ? 1 : 0;
        const int b = c[2] == 0 ? 1 : 2;
        // Corners a and b with counts c[a], c[b]; steps from the lower vertex id.
        const int lo = face[a] < face[b] ? a : b;
        const int hi = lo == a ? b : a;
        key = {1, face[lo], face[hi], c[hi]};
      } else {
        key = {2, f, c[1], c[2]};
      }
      auto [it, inserted] = node_ids.emplace(key, static_cast<int>(tess.points.size()));
      if (inserted) {
        tess.points.push_back(bary[0] * mesh.vertices[face[0]] +
                              bary[1] * mesh.vertices[face[1]] +
                              bary[2] * mesh.vertices[face[2]]);
        tess.point_face.push_back(f);
        tess.point_barycentric.push_back(bary);
      }
      return it->second;
    };
    for (int k = 0; k < kSubTrianglesPerFace; ++k) {
      const auto& corners = SubTriangleCorners(k);
      tess.triangles.emplace_back(node(corners[0]), node(corners[1]), node(corners[2]));
    }
  }
  return tess;
}

}  // namespace facets
