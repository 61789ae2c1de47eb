// RAII wrappers around Embree 3: one device per process (or per test), and a scene
// holding one triangle mesh whose vertex buffer can be updated in place between
// iterations (commit model: fill, commit once, query many times).
//
// Embree works in float: callers pass local object coordinates (double, already
// relative to the block origin) and the scene stores them as float.
#pragma once

#include <embree3/rtcore.h>

#include <Eigen/Core>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace facets {

// Owns an RTCDevice; errors reported by Embree are turned into std::runtime_error at
// the next Check() and logged to stderr by the callback.
class EmbreeDevice {
 public:
  // The device configuration from FACETS_EMBREE_CONFIG (e.g. "isa=avx2"), or Embree's default.
  EmbreeDevice();
  explicit EmbreeDevice(const std::string& config);
  ~EmbreeDevice();
  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;

  RTCDevice get() const { return device_; }
  // Throws if Embree reported an error since the last call.
  void Check() const;

  // A process-wide device, created on first use.
  static EmbreeDevice& Shared();

  // The instruction set of the kernels Embree runs here ("SSE2", "SSE4.2", "AVX", "AVX2",
  // "AVX-512"): the widest the CPU has, capped by an isa= or max_isa= entry of the
  // configuration. Ray hits on triangle edges can differ between them.
  std::string KernelIsa() const;
  // "Embree 3.13.5, AVX-512 kernels" plus the configuration when one was given.
  std::string Describe() const;

 private:
  std::string config_;
  RTCDevice device_ = nullptr;
};

// Sets ray i of a 16-wide packet (float, as Embree wants) and clears its hit.
inline void SetPacketRay(RTCRayHit16* packet, int i, const Eigen::Vector3d& origin,
                         const Eigen::Vector3d& direction,
                         float t_far = std::numeric_limits<float>::infinity()) {
  packet->ray.org_x[i] = static_cast<float>(origin.x());
  packet->ray.org_y[i] = static_cast<float>(origin.y());
  packet->ray.org_z[i] = static_cast<float>(origin.z());
  packet->ray.dir_x[i] = static_cast<float>(direction.x());
  packet->ray.dir_y[i] = static_cast<float>(direction.y());
  packet->ray.dir_z[i] = static_cast<float>(direction.z());
  packet->ray.tnear[i] = 0.0f;
  packet->ray.tfar[i] = t_far;
  packet->ray.time[i] = 0.0f;
  packet->ray.mask[i] = std::numeric_limits<unsigned>::max();
  packet->ray.id[i] = static_cast<unsigned>(i);
  packet->ray.flags[i] = 0;
  packet->hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
  packet->hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
  packet->hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
}

// First hits of a packet of coherent rays (neighbouring pixels, parallel rays).
inline void IntersectCoherent16(const int* valid, RTCScene scene, RTCRayHit16* packet) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  rtcIntersect16(valid, scene, &context, packet);
}

// First hit of one ray. prim_id is the triangle index in the scene's index buffer;
// (u, v) are Embree's barycentrics: point = (1-u-v) V0 + u V1 + v V2.
struct RayHit {
  bool hit = false;
  unsigned geom_id = 0;  // 0: the scene's own triangles, 1: occluders (SetOccluders; their instance id)
  unsigned prim_id = 0;
  float u = 0, v = 0;
  float distance = 0;           // ray parameter t (the direction is not normalised)
  Eigen::Vector3f geom_normal;  // unnormalised, (V1-V0) x (V2-V0)
};

// A static triangle set that stops rays but is not part of a surface (the rest of the
// surface around a window), in its own Embree scene whose BVH is built once. Scenes
// instance it (TriangleScene::SetOccluders), so one build serves every scene of the
// same device that shares it: a window's runs with the same surroundings.
class OccluderScene {
 public:
  OccluderScene(EmbreeDevice& device, const std::vector<Eigen::Vector3d>& vertices,
                const std::vector<Eigen::Vector3i>& triangles);
  ~OccluderScene();
  OccluderScene(const OccluderScene&) = delete;
  OccluderScene& operator=(const OccluderScene&) = delete;

  RTCScene get() const { return scene_; }
  const EmbreeDevice& device() const { return device_; }
  size_t NumTriangles() const { return num_triangles_; }

 private:
  EmbreeDevice& device_;
  RTCScene scene_ = nullptr;
  RTCGeometry mesh_ = nullptr;
  size_t num_triangles_ = 0;
};

// One triangle mesh in its own scene.
class TriangleScene {
 public:
  // vertices: #V by 3 points; triangles: #F by 3 vertex indices. dynamic: the scene
  // will be updated (RTC_SCENE_FLAG_DYNAMIC, Embree's two-level BVH), which is what
  // lets UpdateVertices(..., refit = true) refit instead of rebuild.
  TriangleScene(EmbreeDevice& device, const std::vector<Eigen::Vector3d>& vertices,
                const std::vector<Eigen::Vector3i>& triangles, bool dynamic = false);
  ~TriangleScene();
  TriangleScene(const TriangleScene&) = delete;
  TriangleScene& operator=(const TriangleScene&) = delete;

  // Moves the vertices (same count, same topology) and recommits: no rebuild of the
  // geometry object. refit = false: Embree rebuilds its BVH (best tree for any
  // motion); refit = true: it only refits the existing tree's boxes, much cheaper and
  // as good while the motion is small against the triangle size (the iterations of
  // one window); rebuild after large moves.
  void UpdateVertices(const std::vector<Eigen::Vector3d>& vertices, bool refit = false);

  // Sets a second, static triangle set that stops rays but is not part of the surface:
  // the rest of the surface around a window, which hides parts of the window from
  // oblique views. Replaces the occluders set before (a window whose surface left the
  // region they were selected for). The occluders (an OccluderScene of the same
  // device, kept alive by this scene) are instanced into this one as geometry id 1
  // (identity transform): recommitting this scene after UpdateVertices then refits or
  // rebuilds only the surface, not the occluders. A ray stopped by them has
  // hit.instID[0] == 1 (hit.geomID is 0, the geometry inside the instanced scene). No
  // triangles: no occluders.
  void SetOccluders(std::shared_ptr<const OccluderScene> occluders);
  bool HasOccluders() const { return occluder_ != nullptr; }

  size_t NumVertices() const { return num_vertices_; }
  size_t NumTriangles() const { return num_triangles_; }
  RTCScene get() const { return scene_; }

  // Single ray, first hit only, within [t_near, t_far].
  RayHit Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                   float t_near = 0.0f, float t_far = 1e30f) const;
  // Whether any triangle (either side) lies on the ray within [t_near, t_far]: Embree's
  // occlusion query, cheaper than Intersect when the first hit itself is not needed.
  bool Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                float t_near, float t_far) const;

 private:
  EmbreeDevice& device_;
  RTCScene scene_ = nullptr;
  RTCGeometry geometry_ = nullptr;
  std::shared_ptr<const OccluderScene> occluder_scene_;
  RTCGeometry occluder_ = nullptr;  // the instance of occluder_scene_
  float* vertex_buffer_ = nullptr;  // owned by Embree, 3 floats + 1 pad per vertex
  size_t num_vertices_ = 0;
  size_t num_triangles_ = 0;
};

}  // namespace facets
