#include "visibility/occluder_selection.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <stdexcept>

namespace facets {
namespace {

// Box in the camera frame enclosing the world box (centre transformed, half extents
// through |R|).
Eigen::AlignedBox3d CameraBox(const Eigen::AlignedBox3d& box, const Eigen::Matrix3d& rotation,
                              const Eigen::Matrix3d& abs_rotation, const Eigen::Vector3d& translation) {
  const Eigen::Vector3d centre = rotation * box.center() + translation;
  const Eigen::Vector3d half = abs_rotation * (0.5 * box.sizes());
  return Eigen::AlignedBox3d(centre - half, centre + half);
}

// Normalised-coordinate rectangle (x/z, y/z) covering the part of a camera-frame box
// with z >= z_near (> 0): x/z over a box is extreme at its corners.
Eigen::AlignedBox2d Normalised(const Eigen::AlignedBox3d& cam_box, double z_near) {
  const double z0 = std::max(cam_box.min().z(), z_near), z1 = std::max(cam_box.max().z(), z_near);
  Eigen::AlignedBox2d rect;
  for (double z : {z0, z1}) {
    for (double x : {cam_box.min().x(), cam_box.max().x()}) {
      for (double y : {cam_box.min().y(), cam_box.max().y()}) rect.extend(Eigen::Vector2d(x / z, y / z));
    }
  }
  return rect;
}

}  // namespace

std::vector<Eigen::AlignedBox3d> FaceBoxes(const Tessellation& tessellation) {
  if (tessellation.triangles.size() % kSubTrianglesPerFace != 0) {
    throw std::invalid_argument("FaceBoxes: sub-triangle count is not a multiple of 16");
  }
  const int num_faces = static_cast<int>(tessellation.triangles.size() / kSubTrianglesPerFace);
  std::vector<Eigen::AlignedBox3d> boxes(num_faces);
  tbb::parallel_for(tbb::blocked_range<int>(0, num_faces, 1024), [&](const tbb::blocked_range<int>& range) {
    for (int f = range.begin(); f != range.end(); ++f) {
      Eigen::AlignedBox3d box;
      for (int s = 0; s < kSubTrianglesPerFace; ++s) {
        const Eigen::Vector3i& tri = tessellation.triangles[f * kSubTrianglesPerFace + s];
        for (int c = 0; c < 3; ++c) box.extend(tessellation.points[tri[c]]);
      }
      boxes[f] = box;
    }
  });
  return boxes;
}

std::vector<int> FacesThatCanHide(const std::vector<Eigen::AlignedBox3d>& face_boxes,
                                  const Eigen::AlignedBox3d& target,
                                  const std::vector<OccluderView>& views) {
  struct ViewTest {
    Eigen::Matrix3d rotation, abs_rotation;
    Eigen::Vector3d translation;
    Eigen::AlignedBox2d rect;  // target, normalised coordinates
    double z_far = 0.0;        // deepest camera z of the target
    double z_near = 0.0;       // image-plane guard for faces
  };
  std::vector<ViewTest> tests;
  if (target.isEmpty()) return {};
  for (const OccluderView& view : views) {
    ViewTest t;
    t.rotation = view.cam_from_world.rotation.toRotationMatrix();
    t.abs_rotation = t.rotation.cwiseAbs();
    t.translation = view.cam_from_world.translation;
    const Eigen::AlignedBox3d cam_target = CameraBox(target, t.rotation, t.abs_rotation, t.translation);
    if (cam_target.max().z() <= 0.0) continue;  // the target is behind this camera
    t.z_far = cam_target.max().z();
    t.z_near = 1e-9 * std::max(1.0, target.diagonal().norm());
    if (cam_target.min().z() <= t.z_near) {
      // The target reaches behind the image plane: every face in front can hide it.
      t.rect = Eigen::AlignedBox2d(Eigen::Vector2d::Constant(-1e300), Eigen::Vector2d::Constant(1e300));
    } else {
      t.rect = Normalised(cam_target, t.z_near);
    }
    if (view.camera != nullptr) {
      // Only rays of the image's pixels are cast.
      Eigen::AlignedBox2d fov;
      const Camera& camera = *view.camera;
      for (double px : {0.0, static_cast<double>(camera.width)}) {
        for (double py : {0.0, static_cast<double>(camera.height)}) {
          if (camera.HasDistortion()) {
            fov.setEmpty();
            break;
          }
          fov.extend(Eigen::Vector2d((px - camera.PrincipalX()) / camera.FocalX(),
                                     (py - camera.PrincipalY()) / camera.FocalY()));
        }
        if (fov.isEmpty()) break;
      }
      if (!fov.isEmpty()) {
        // Half a pixel of slack against rounding.
        fov.extend(fov.min() - Eigen::Vector2d(1.0 / camera.FocalX(), 1.0 / camera.FocalY()));
        fov.extend(fov.max() + Eigen::Vector2d(1.0 / camera.FocalX(), 1.0 / camera.FocalY()));
        t.rect = t.rect.intersection(fov);
        if (t.rect.isEmpty()) continue;
      }
    }
    tests.push_back(t);
  }
  std::vector<int> selected;
  if (tests.empty()) return selected;
  const int num_faces = static_cast<int>(face_boxes.size());
  std::vector<char> keep(num_faces, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, num_faces, 2048), [&](const tbb::blocked_range<int>& range) {
    for (int f = range.begin(); f != range.end(); ++f) {
      const Eigen::AlignedBox3d& box = face_boxes[f];
      if (box.isEmpty()) continue;
      for (const ViewTest& t : tests) {
        const Eigen::AlignedBox3d cam_box = CameraBox(box, t.rotation, t.abs_rotation, t.translation);
        if (cam_box.max().z() <= 0.0) continue;      // behind the camera
        if (cam_box.min().z() >= t.z_far) continue;  // entirely deeper than the target
        if (cam_box.min().z() > t.z_near && !Normalised(cam_box, t.z_near).intersects(t.rect)) continue;
        keep[f] = 1;
        break;
      }
    }
  });
  for (int f = 0; f < num_faces; ++f) {
    if (keep[f]) selected.push_back(f);
  }
  return selected;
}

}  // namespace facets
