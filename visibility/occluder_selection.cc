#include "visibility/occluder_selection.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <unordered_map>
#include <utility>

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

namespace {

// One view's test: the window's projection in normalised coordinates, cut into a grid
// of cells that each hold the deepest camera z of the window geometry projecting into
// them. A ray through a cell meets the window no deeper than that z, so a face whose
// box starts deeper in every cell it covers cannot stand in front of the window.
struct ViewDepthGrid {
  static constexpr int kCells = 16;
  Eigen::Matrix3d rotation, abs_rotation;
  Eigen::Vector3d translation;
  Eigen::AlignedBox2d rect;  // the window's projection, normalised coordinates
  double z_near = 0.0;       // image-plane guard for boxes
  double z_far = 0.0;        // deepest camera z of the window
  bool behind = false;       // the window reaches behind the image plane: z_far alone decides
  std::vector<double> cell_z = std::vector<double>(kCells * kCells, -1e300);

  Eigen::AlignedBox3d ToCamera(const Eigen::AlignedBox3d& box) const {
    return CameraBox(box, rotation, abs_rotation, translation);
  }
  // Cells [x0, x1] x [y0, y1] covered by a normalised rectangle; false if none.
  bool Cells(const Eigen::AlignedBox2d& r, int* x0, int* x1, int* y0, int* y1) const {
    const Eigen::AlignedBox2d cut = r.intersection(rect);
    if (cut.isEmpty()) return false;
    const Eigen::Vector2d scale = Eigen::Vector2d::Constant(kCells).cwiseQuotient(rect.sizes());
    auto cell = [&](double v, double lo, double s) {
      const double t = (v - lo) * s;  // NaN or out of range lands on the edge cells
      if (!(t > 0.0)) return 0;
      return t < kCells ? static_cast<int>(t) : kCells - 1;
    };
    *x0 = cell(cut.min().x(), rect.min().x(), scale.x());
    *x1 = cell(cut.max().x(), rect.min().x(), scale.x());
    *y0 = cell(cut.min().y(), rect.min().y(), scale.y());
    *y1 = cell(cut.max().y(), rect.min().y(), scale.y());
    return true;
  }
  bool CanHide(const Eigen::AlignedBox3d& box) const;
};

// Conservative for boxes: a box inside one that cannot hide cannot hide either. A face
// touching the window at its deepest point is kept (ties of equal depth).
bool ViewDepthGrid::CanHide(const Eigen::AlignedBox3d& box) const {
  const Eigen::AlignedBox3d cam_box = ToCamera(box);
  if (cam_box.max().z() <= 0.0) return false;      // behind the camera
  if (cam_box.min().z() > z_far) return false;     // entirely deeper than the window
  if (behind || cam_box.min().z() <= z_near) return true;
  int x0, x1, y0, y1;
  if (!Cells(Normalised(cam_box, z_near), &x0, &x1, &y0, &y1)) return false;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      if (cam_box.min().z() <= cell_z[y * kCells + x]) return true;
    }
  }
  return false;
}

// The normalised rectangle of the image's pixels, half a pixel wider against rounding;
// empty with lens distortion (then the window's projection is not cut to the image).
Eigen::AlignedBox2d PixelField(const Camera& camera) {
  Eigen::AlignedBox2d fov;
  if (camera.HasDistortion()) return fov;
  for (double px : {-1.0, camera.width + 1.0}) {
    for (double py : {-1.0, camera.height + 1.0}) {
      fov.extend(Eigen::Vector2d((px - camera.PrincipalX()) / camera.FocalX(),
                                 (py - camera.PrincipalY()) / camera.FocalY()));
    }
  }
  return fov;
}

// The view's depth grid over the window's boxes (each grown by `slack`); nullopt when
// the window lies behind the camera or outside its image.
std::optional<ViewDepthGrid> MakeDepthGrid(const std::vector<Eigen::AlignedBox3d>& window_boxes,
                                           double slack, const OccluderView& view) {
  ViewDepthGrid g;
  g.rotation = view.cam_from_world.rotation.toRotationMatrix();
  g.abs_rotation = g.rotation.cwiseAbs();
  g.translation = view.cam_from_world.translation;
  std::vector<Eigen::AlignedBox3d> cam_boxes;
  Eigen::AlignedBox3d all;
  for (const Eigen::AlignedBox3d& box : window_boxes) {
    if (box.isEmpty()) continue;
    const Eigen::Vector3d grow = Eigen::Vector3d::Constant(slack);
    cam_boxes.push_back(g.ToCamera(Eigen::AlignedBox3d(box.min() - grow, box.max() + grow)));
    all.extend(cam_boxes.back());
  }
  if (all.isEmpty() || all.max().z() <= 0.0) return std::nullopt;
  g.z_far = all.max().z();
  g.z_near = 1e-9 * std::max(1.0, all.diagonal().norm());
  if (all.min().z() <= g.z_near) {
    g.behind = true;
    return g;
  }
  g.rect = Normalised(all, g.z_near);
  if (view.camera != nullptr) {
    const Eigen::AlignedBox2d fov = PixelField(*view.camera);
    if (!fov.isEmpty()) g.rect = g.rect.intersection(fov);
  }
  if (g.rect.isEmpty() || g.rect.sizes().minCoeff() <= 0.0) return std::nullopt;
  for (const Eigen::AlignedBox3d& cam_box : cam_boxes) {
    int x0, x1, y0, y1;
    if (!g.Cells(Normalised(cam_box, g.z_near), &x0, &x1, &y0, &y1)) continue;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        double& z = g.cell_z[y * ViewDepthGrid::kCells + x];
        z = std::max(z, cam_box.max().z());
      }
    }
  }
  return g;
}

}  // namespace

FaceBoxIndex::FaceBoxIndex(std::vector<Eigen::AlignedBox3d> face_boxes) : faces_(std::move(face_boxes)) {
  constexpr double kFacesPerCluster = 64.0;
  Eigen::AlignedBox3d all;
  for (const Eigen::AlignedBox3d& box : faces_) {
    if (!box.isEmpty()) all.extend(box.center());
  }
  if (all.isEmpty()) return;
  // Cubic cells, sized for kFacesPerCluster faces if the faces filled the box's largest
  // face (a surface, not a volume), at most 1025 along an axis (faces along a line).
  const Eigen::Vector3d size = all.sizes();
  const double area = std::max({size.x() * size.y(), size.x() * size.z(), size.y() * size.z()});
  const double cell = std::max({std::sqrt(area * kFacesPerCluster / static_cast<double>(faces_.size())),
                                size.maxCoeff() / 1024.0, 1e-9});
  std::unordered_map<long long, int> cluster_of_cell;  // key: cell index, 21 bits per axis
  for (int f = 0; f < static_cast<int>(faces_.size()); ++f) {
    if (faces_[f].isEmpty()) continue;
    const Eigen::Vector3d c = ((faces_[f].center() - all.min()) / cell).array().floor().cwiseMax(0.0).cwiseMin(1024.0);
    const long long key = (static_cast<long long>(c.z()) << 42) | (static_cast<long long>(c.y()) << 21) |
                          static_cast<long long>(c.x());
    const auto [it, added] = cluster_of_cell.emplace(key, static_cast<int>(clusters_.size()));
    if (added) {
      clusters_.emplace_back();
      cluster_boxes_.emplace_back();
    }
    clusters_[it->second].push_back(f);
    cluster_boxes_[it->second].extend(faces_[f]);
  }
}

std::vector<int> FacesThatCanHide(const FaceBoxIndex& surface,
                                  const std::vector<Eigen::AlignedBox3d>& window_boxes, double slack,
                                  const std::vector<OccluderView>& views) {
  std::vector<ViewDepthGrid> grids;
  for (const OccluderView& view : views) {
    if (std::optional<ViewDepthGrid> g = MakeDepthGrid(window_boxes, slack, view)) grids.push_back(std::move(*g));
  }
  std::vector<int> selected;
  if (grids.empty()) return selected;
  const std::vector<Eigen::AlignedBox3d>& faces = surface.faces();
  std::vector<char> keep(faces.size(), 0);
  const int num_clusters = static_cast<int>(surface.clusters().size());
  tbb::parallel_for(tbb::blocked_range<int>(0, num_clusters, 16), [&](const tbb::blocked_range<int>& range) {
    std::vector<const ViewDepthGrid*> passed;
    for (int c = range.begin(); c != range.end(); ++c) {
      passed.clear();
      for (const ViewDepthGrid& g : grids) {
        if (g.CanHide(surface.cluster_boxes()[c])) passed.push_back(&g);
      }
      if (passed.empty()) continue;
      for (int f : surface.clusters()[c]) {
        for (const ViewDepthGrid* g : passed) {
          if (!g->CanHide(faces[f])) continue;
          keep[f] = 1;
          break;
        }
      }
    }
  });
  for (size_t f = 0; f < faces.size(); ++f) {
    if (keep[f]) selected.push_back(static_cast<int>(f));
  }
  return selected;
}

}  // namespace facets
