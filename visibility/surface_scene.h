// The Embree scene of the tessellated G1 surface (DESIGN.md sections 3, 4): one
// Embree triangle per sub-triangle (= grey facet), in the Tessellation's order, so
// Embree's primitive id is the facet index s (face s / 16, local index s % 16).
//
// Between iterations of a window adjustment only the vertices move: Update() then
// writes the new positions into Embree's vertex buffer and recommits (Embree refits
// its BVH) instead of building a new scene. A changed topology (other triangles or
// another point count, e.g. after subdivision or an edge flip) rebuilds.
#pragma once

#include <memory>
#include <vector>

#include "mesh/tessellation.h"
#include "visibility/embree_scene.h"

namespace facets {

class SurfaceScene {
 public:
  // Throws std::invalid_argument when the triangle count is not a multiple of 16, an
  // index is out of range or a point is not finite.
  // refittable: build Embree's dynamic (two-level) BVH so that Update() can refit it;
  // false builds the static single-level BVH, which queries a little faster but is
  // rebuilt on every Update() (see docs/bench/visibility.md for both).
  SurfaceScene(EmbreeDevice& device, const Tessellation& tessellation,
               bool refittable = true);
  explicit SurfaceScene(const Tessellation& tessellation, bool refittable = true)
      : SurfaceScene(EmbreeDevice::Shared(), tessellation, refittable) {}

  // Triangles that hide parts of this surface without belonging to it (the surface
  // around a window); kept across rebuilds. Rays that hit them first are kOccluded.
  // They are instanced into the scene as it stands (replacing earlier ones) without
  // rebuilding the surface's BVH. The occluders must belong to this scene's device.
  void SetOccluders(std::shared_ptr<const OccluderScene> occluders);
  void SetOccluders(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3i>& triangles);

  enum class UpdateKind { kMovedVertices, kRebuilt };
  // Moves the vertices in place when the topology is unchanged, rebuilds otherwise.
  // refit (default; only with a refittable scene): Embree only refits its BVH to the moved vertices, right for the
  // small normal displacements between iterations of one window; pass false after
  // large motions (e.g. object lifting) so the tree is rebuilt for the new shape.
  UpdateKind Update(const Tessellation& tessellation, bool refit = true);

  int NumFacets() const { return static_cast<int>(triangles_.size()); }
  int NumFaces() const { return NumFacets() / kSubTrianglesPerFace; }
  int NumPoints() const { return static_cast<int>(scene_->NumVertices()); }
  // How many times the Embree scene was built from scratch (1 after construction).
  int NumBuilds() const { return num_builds_; }

  RTCScene get() const { return scene_->get(); }
  const TriangleScene& triangle_scene() const { return *scene_; }
  EmbreeDevice& device() const { return device_; }

 private:
  static void Validate(const Tessellation& tessellation);

  EmbreeDevice& device_;
  std::vector<Eigen::Vector3i> triangles_;  // topology of the current scene
  std::unique_ptr<TriangleScene> scene_;
  bool refittable_ = true;
  std::shared_ptr<const OccluderScene> occluders_;
  int num_builds_ = 0;
};

}  // namespace facets
