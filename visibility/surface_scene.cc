#include "visibility/surface_scene.h"

#include <stdexcept>
#include <string>

namespace facets {

void SurfaceScene::Validate(const Tessellation& tessellation) {
  if (tessellation.triangles.size() % kSubTrianglesPerFace != 0) {
    throw std::invalid_argument(
        "SurfaceScene: " + std::to_string(tessellation.triangles.size()) +
        " sub-triangles is not a multiple of " + std::to_string(kSubTrianglesPerFace));
  }
  for (size_t i = 0; i < tessellation.points.size(); ++i) {
    if (!tessellation.points[i].allFinite()) {
      throw std::invalid_argument("SurfaceScene: tessellation point " + std::to_string(i) +
                                  " is not finite");
    }
  }
}

SurfaceScene::SurfaceScene(EmbreeDevice& device, const Tessellation& tessellation,
                           bool refittable)
    : device_(device), refittable_(refittable) {
  Validate(tessellation);
  // TriangleScene checks the index range.
  scene_ = std::make_unique<TriangleScene>(device_, tessellation.points,
                                           tessellation.triangles, refittable_);
  triangles_ = tessellation.triangles;
  num_builds_ = 1;
}

SurfaceScene::UpdateKind SurfaceScene::Update(const Tessellation& tessellation,
                                              bool refit) {
  Validate(tessellation);
  if (tessellation.points.size() == scene_->NumVertices() &&
      tessellation.triangles == triangles_) {
    scene_->UpdateVertices(tessellation.points, refit && refittable_);
    return UpdateKind::kMovedVertices;
  }
  auto scene = std::make_unique<TriangleScene>(device_, tessellation.points,
                                               tessellation.triangles, refittable_);
  if (occluders_) scene->SetOccluders(occluders_);
  scene_ = std::move(scene);
  triangles_ = tessellation.triangles;
  ++num_builds_;
  return UpdateKind::kRebuilt;
}

void SurfaceScene::SetOccluders(std::shared_ptr<const OccluderScene> occluders) {
  occluders_ = std::move(occluders);
  scene_->SetOccluders(occluders_);
}

void SurfaceScene::SetOccluders(const std::vector<Eigen::Vector3d>& points,
                                const std::vector<Eigen::Vector3i>& triangles) {
  SetOccluders(std::make_shared<const OccluderScene>(device_, points, triangles));
}

}  // namespace facets
