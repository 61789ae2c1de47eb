#include "visibility/embree_scene.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>

namespace facets {
namespace {

thread_local std::string last_embree_error;

void ErrorCallback(void*, RTCError code, const char* message) {
  last_embree_error = "Embree error " + std::to_string(static_cast<int>(code)) + ": " +
                      (message ? message : "");
  std::fprintf(stderr, "%s\n", last_embree_error.c_str());
}

// 0 SSE2, 1 SSE4.2, 2 AVX, 3 AVX2, 4 AVX-512 (Embree's AVX-512 kernels need F, CD, DQ, BW, VL).
int CpuIsaRank() {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
      __builtin_cpu_supports("avx512vl")) {
    return 4;
  }
  if (__builtin_cpu_supports("avx2")) return 3;
  if (__builtin_cpu_supports("avx")) return 2;
  if (__builtin_cpu_supports("sse4.2")) return 1;
  return 0;
}

// The value of `key` ("isa=") in a comma- or space-separated configuration, or "".
std::string ConfigValue(const std::string& config, const std::string& key) {
  for (std::size_t at = config.find(key); at != std::string::npos; at = config.find(key, at + 1)) {
    if (at > 0 && config[at - 1] != ',' && config[at - 1] != ' ') continue;  // "max_isa=" holds "isa="
    const std::size_t begin = at + key.size();
    return config.substr(begin, config.find_first_of(", ", begin) - begin);
  }
  return "";
}

// The rank an isa= or max_isa= entry of an Embree configuration allows (4 when none).
int ConfiguredIsaCap(const std::string& config) {
  int cap = 4;
  for (const char* key : {"isa=", "max_isa="}) {
    const std::string value = ConfigValue(config, key);
    if (value == "sse" || value == "sse2" || value == "sse3" || value == "ssse3" || value == "sse4.1") {
      cap = std::min(cap, 0);
    } else if (value == "sse4.2") {
      cap = std::min(cap, 1);
    } else if (value == "avx" || value == "avxi") {
      cap = std::min(cap, 2);
    } else if (value == "avx2") {
      cap = std::min(cap, 3);
    }
  }
  return cap;
}

}  // namespace

// Embree picks its kernels by the CPU (SSE4.2, AVX2, AVX-512), and ray hits on edges,
// and every decision that follows from them, can differ between machines.
// FACETS_EMBREE_CONFIG passes a device configuration, e.g. "isa=avx2", to compare runs
// across machines.
EmbreeDevice::EmbreeDevice()
    : EmbreeDevice(std::getenv("FACETS_EMBREE_CONFIG") ? std::getenv("FACETS_EMBREE_CONFIG") : "") {}

EmbreeDevice::EmbreeDevice(const std::string& config) : config_(config) {
  device_ = rtcNewDevice(config_.empty() ? nullptr : config_.c_str());
  if (!device_) {
    throw std::runtime_error("Embree: cannot create a device (error " +
                             std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) +
                             (config_.empty() ? "" : ", configuration \"" + config_ + "\"") + ")");
  }
  rtcSetDeviceErrorFunction(device_, ErrorCallback, nullptr);
}

std::string EmbreeDevice::KernelIsa() const {
  static const char* const kNames[] = {"SSE2", "SSE4.2", "AVX", "AVX2", "AVX-512"};
  const int isa = std::min(CpuIsaRank(), ConfiguredIsaCap(config_));
  return kNames[isa];
}

std::string EmbreeDevice::Describe() const {
  const long version = static_cast<long>(rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_VERSION));
  std::string text = "Embree " + std::to_string(version / 10000) + "." + std::to_string(version / 100 % 100) + "." +
                     std::to_string(version % 100) + ", " + KernelIsa() + " kernels";
  if (!config_.empty()) text += " (configuration \"" + config_ + "\")";
  return text;
}

EmbreeDevice::~EmbreeDevice() { rtcReleaseDevice(device_); }

void EmbreeDevice::Check() const {
  const RTCError code = rtcGetDeviceError(device_);
  if (code != RTC_ERROR_NONE) {
    throw std::runtime_error(last_embree_error.empty()
                                 ? "Embree error " + std::to_string(static_cast<int>(code))
                                 : last_embree_error);
  }
}

EmbreeDevice& EmbreeDevice::Shared() {
  static EmbreeDevice device;
  return device;
}

TriangleScene::TriangleScene(EmbreeDevice& device,
                             const std::vector<Eigen::Vector3d>& vertices,
                             const std::vector<Eigen::Vector3i>& triangles,
                             bool dynamic)
    : device_(device), num_vertices_(vertices.size()), num_triangles_(triangles.size()) {
  scene_ = rtcNewScene(device.get());
  rtcSetSceneFlags(scene_, dynamic ? RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC
                                   : RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
  geometry_ = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
  // 4 floats per vertex: Embree may read 16 bytes past the last vertex otherwise.
  vertex_buffer_ = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry_, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 4 * sizeof(float),
      num_vertices_));
  auto* index_buffer = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geometry_, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
      num_triangles_));
  device.Check();
  for (size_t i = 0; i < num_triangles_; ++i) {
    for (int k = 0; k < 3; ++k) {
      const int index = triangles[i][k];
      if (index < 0 || static_cast<size_t>(index) >= num_vertices_) {
        throw std::invalid_argument("TriangleScene: triangle " + std::to_string(i) +
                                    " has vertex index out of range");
      }
      index_buffer[3 * i + k] = static_cast<unsigned>(index);
    }
  }
  UpdateVertices(vertices);
  rtcAttachGeometry(scene_, geometry_);
  rtcCommitScene(scene_);
  device.Check();
}

TriangleScene::~TriangleScene() {
  if (occluder_ != nullptr) rtcReleaseGeometry(occluder_);
  rtcReleaseGeometry(geometry_);
  rtcReleaseScene(scene_);
}

void TriangleScene::UpdateVertices(const std::vector<Eigen::Vector3d>& vertices,
                                   bool refit) {
  if (vertices.size() != num_vertices_) {
    throw std::invalid_argument("TriangleScene::UpdateVertices: vertex count changed");
  }
  for (size_t i = 0; i < num_vertices_; ++i) {
    vertex_buffer_[4 * i + 0] = static_cast<float>(vertices[i].x());
    vertex_buffer_[4 * i + 1] = static_cast<float>(vertices[i].y());
    vertex_buffer_[4 * i + 2] = static_cast<float>(vertices[i].z());
    vertex_buffer_[4 * i + 3] = 0.0f;
  }
  rtcSetGeometryBuildQuality(geometry_,
                             refit ? RTC_BUILD_QUALITY_REFIT : RTC_BUILD_QUALITY_MEDIUM);
  rtcUpdateGeometryBuffer(geometry_, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(geometry_);
  // The scene needs a recommit after its geometry changed (harmless before attach).
  rtcCommitScene(scene_);
  device_.Check();
}

OccluderScene::OccluderScene(EmbreeDevice& device, const std::vector<Eigen::Vector3d>& vertices,
                             const std::vector<Eigen::Vector3i>& triangles)
    : device_(device), num_triangles_(triangles.size()) {
  scene_ = rtcNewScene(device_.get());
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
  if (triangles.empty()) {
    rtcCommitScene(scene_);
    device_.Check();
    return;
  }
  mesh_ = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertex_buffer = static_cast<float*>(rtcSetNewGeometryBuffer(
      mesh_, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 4 * sizeof(float), vertices.size()));
  auto* index_buffer = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      mesh_, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles.size()));
  device_.Check();
  for (size_t i = 0; i < vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) vertex_buffer[4 * i + k] = static_cast<float>(vertices[i][k]);
    vertex_buffer[4 * i + 3] = 0.0f;
  }
  for (size_t i = 0; i < triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const int index = triangles[i][k];
      if (index < 0 || static_cast<size_t>(index) >= vertices.size()) {
        throw std::invalid_argument("OccluderScene: triangle " + std::to_string(i) +
                                    " has vertex index out of range");
      }
      index_buffer[3 * i + k] = static_cast<unsigned>(index);
    }
  }
  rtcCommitGeometry(mesh_);
  rtcAttachGeometry(scene_, mesh_);
  rtcCommitScene(scene_);
  device_.Check();
}

OccluderScene::~OccluderScene() {
  if (mesh_ != nullptr) rtcReleaseGeometry(mesh_);
  rtcReleaseScene(scene_);
}

void TriangleScene::SetOccluders(std::shared_ptr<const OccluderScene> occluders) {
  if (occluders && &occluders->device() != &device_) {
    throw std::invalid_argument("TriangleScene: the occluders belong to another Embree device");
  }
  const bool none = !occluders || occluders->NumTriangles() == 0;
  if (occluder_ == nullptr && none) return;
  if (occluder_ != nullptr) {
    rtcDetachGeometry(scene_, 1);
    rtcReleaseGeometry(occluder_);
    occluder_ = nullptr;
    occluder_scene_.reset();
  }
  if (!none) {
    occluder_scene_ = std::move(occluders);
    occluder_ = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(occluder_, occluder_scene_->get());
    rtcSetGeometryTimeStepCount(occluder_, 1);
    const float identity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};  // 3x4 column-major
    rtcSetGeometryTransform(occluder_, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, identity);
    rtcCommitGeometry(occluder_);
    rtcAttachGeometryByID(scene_, occluder_, 1);
  }
  rtcCommitScene(scene_);
  device_.Check();
}

RayHit TriangleScene::Intersect(const Eigen::Vector3d& origin,
                                const Eigen::Vector3d& direction, float t_near,
                                float t_far) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rayhit;
  rayhit.ray.org_x = static_cast<float>(origin.x());
  rayhit.ray.org_y = static_cast<float>(origin.y());
  rayhit.ray.org_z = static_cast<float>(origin.z());
  rayhit.ray.dir_x = static_cast<float>(direction.x());
  rayhit.ray.dir_y = static_cast<float>(direction.y());
  rayhit.ray.dir_z = static_cast<float>(direction.z());
  rayhit.ray.tnear = t_near;
  rayhit.ray.tfar = t_far;
  rayhit.ray.mask = std::numeric_limits<unsigned>::max();
  rayhit.ray.flags = 0;
  rayhit.ray.time = 0;
  rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_, &context, &rayhit);
  RayHit result;
  if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return result;
  result.hit = true;
  result.geom_id = rayhit.hit.instID[0] != RTC_INVALID_GEOMETRY_ID ? rayhit.hit.instID[0] : rayhit.hit.geomID;
  result.prim_id = rayhit.hit.primID;
  result.u = rayhit.hit.u;
  result.v = rayhit.hit.v;
  result.distance = rayhit.ray.tfar;
  result.geom_normal = Eigen::Vector3f(rayhit.hit.Ng_x, rayhit.hit.Ng_y, rayhit.hit.Ng_z);
  return result;
}

bool TriangleScene::Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                             float t_near, float t_far) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray;
  ray.org_x = static_cast<float>(origin.x());
  ray.org_y = static_cast<float>(origin.y());
  ray.org_z = static_cast<float>(origin.z());
  ray.dir_x = static_cast<float>(direction.x());
  ray.dir_y = static_cast<float>(direction.y());
  ray.dir_z = static_cast<float>(direction.z());
  ray.tnear = t_near;
  ray.tfar = t_far;
  ray.mask = std::numeric_limits<unsigned>::max();
  ray.flags = 0;
  ray.time = 0;
  rtcOccluded1(scene_, &context, &ray);
  // Embree sets tfar to -inf when the ray is blocked.
  return ray.tfar < 0.0f;
}

}  // namespace facets
