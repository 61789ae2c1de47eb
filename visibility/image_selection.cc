#include "visibility/image_selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace facets {
namespace {

// Normalised coordinates (undistorted x/z, y/z) of the image's field of view: the
// bounding rectangle of the undistorted image border, sampled densely.
Eigen::AlignedBox2d FieldOfView(const Camera& camera) {
  Eigen::AlignedBox2d fov;
  constexpr int kSamples = 64;
  for (int i = 0; i <= kSamples; ++i) {
    const double x = camera.width * static_cast<double>(i) / kSamples;
    const double y = camera.height * static_cast<double>(i) / kSamples;
    for (const Eigen::Vector2d& pixel :
         {Eigen::Vector2d(x, 0), Eigen::Vector2d(x, camera.height), Eigen::Vector2d(0, y),
          Eigen::Vector2d(camera.width, y)}) {
      fov.extend(camera.CamFromImage(pixel).head<2>());
    }
  }
  return fov;
}

}  // namespace

std::optional<PixelRect> ProjectBox(const Eigen::AlignedBox3d& box, const Camera& camera,
                                    const Rigid3d& cam_from_world, int margin_px) {
  if (box.isEmpty()) return std::nullopt;
  const PixelRect full = PixelRect::Full(camera);
  Eigen::AlignedBox2d normalised;
  int in_front = 0;
  // Corners closer than this (relative to the box size) to the camera plane would
  // blow up the projection: treat them like corners behind it.
  const double z_min = 1e-9 * std::max(1.0, box.diagonal().norm());
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner =
        box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k));
    const Eigen::Vector3d in_cam = cam_from_world * corner;
    if (in_cam.z() > z_min) {
      ++in_front;
      normalised.extend(in_cam.head<2>() / in_cam.z());
    }
  }
  if (in_front == 0) return std::nullopt;
  if (in_front < 8) return full;
  PixelRect rect;
  if (!camera.HasDistortion()) {
    const Eigen::Vector2d lo(camera.FocalX() * normalised.min().x() + camera.PrincipalX(),
                             camera.FocalY() * normalised.min().y() + camera.PrincipalY());
    const Eigen::Vector2d hi(camera.FocalX() * normalised.max().x() + camera.PrincipalX(),
                             camera.FocalY() * normalised.max().y() + camera.PrincipalY());
    // Pixel x covers [x, x + 1): the rectangle holds every pixel the hull touches.
    const double big = 1e9;
    rect = PixelRect{static_cast<int>(std::floor(std::clamp(lo.x(), -big, big))) - margin_px,
                     static_cast<int>(std::floor(std::clamp(lo.y(), -big, big))) - margin_px,
                     static_cast<int>(std::floor(std::clamp(hi.x(), -big, big))) + 1 + margin_px,
                     static_cast<int>(std::floor(std::clamp(hi.y(), -big, big))) + 1 + margin_px};
  } else {
    const Eigen::AlignedBox2d clipped = normalised.intersection(FieldOfView(camera));
    if (clipped.isEmpty()) return std::nullopt;
    Eigen::AlignedBox2d pixels;
    constexpr int kSamples = 16;
    for (int i = 0; i <= kSamples; ++i) {
      const double s = static_cast<double>(i) / kSamples;
      const Eigen::Vector2d a = clipped.min(), b = clipped.max();
      for (const Eigen::Vector2d& p :
           {Eigen::Vector2d(a.x() + s * (b.x() - a.x()), a.y()),
            Eigen::Vector2d(a.x() + s * (b.x() - a.x()), b.y()),
            Eigen::Vector2d(a.x(), a.y() + s * (b.y() - a.y())),
            Eigen::Vector2d(b.x(), a.y() + s * (b.y() - a.y()))}) {
        pixels.extend(camera.ImageFromCam(Eigen::Vector3d(p.x(), p.y(), 1.0)));
      }
    }
    rect = PixelRect{static_cast<int>(std::floor(pixels.min().x())) - margin_px,
                     static_cast<int>(std::floor(pixels.min().y())) - margin_px,
                     static_cast<int>(std::floor(pixels.max().x())) + 1 + margin_px,
                     static_cast<int>(std::floor(pixels.max().y())) + 1 + margin_px};
  }
  rect = rect.Intersection(full);
  if (rect.Empty()) return std::nullopt;
  return rect;
}

std::vector<ImageSelection> SelectImages(const Eigen::AlignedBox3d& box,
                                         const ImageBlock& block, int margin_px) {
  std::vector<ImageSelection> selection;
  for (int i = 0; i < static_cast<int>(block.images.size()); ++i) {
    const BlockImage& image = block.images[i];
    const auto rect =
        ProjectBox(box, block.CameraOf(image), image.cam_from_world, margin_px);
    if (rect) selection.push_back({i, image.image_id, *rect});
  }
  return selection;
}

std::vector<ImageCast> CastWindow(const SurfaceScene& scene, const ImageBlock& block,
                                  const Eigen::AlignedBox3d& box, const CastOptions& options,
                                  int margin_px) {
  std::vector<ImageCast> casts;
  for (const ImageSelection& selection : SelectImages(box, block, margin_px)) {
    casts.push_back(
        {selection, CastPixels(scene, block, selection.image_index, selection.rect, options)});
  }
  return casts;
}

std::vector<PixelRect> ProjectedBlocks(const std::vector<Eigen::AlignedBox3d>& boxes,
                                       const Camera& camera, const Rigid3d& cam_from_world,
                                       const PixelRect& clip_in, int block_size, int margin_px) {
  if (block_size < 1) throw std::invalid_argument("ProjectedBlocks: block_size must be >= 1");
  std::vector<PixelRect> blocks;
  const PixelRect clip = clip_in.Intersection(PixelRect::Full(camera));
  if (clip.Empty()) return blocks;
  const int bx0 = clip.x0 / block_size, by0 = clip.y0 / block_size;
  const int bx1 = (clip.x1 + block_size - 1) / block_size, by1 = (clip.y1 + block_size - 1) / block_size;
  const int nx = bx1 - bx0, ny = by1 - by0;
  std::vector<char> on(static_cast<size_t>(nx) * ny, 0);
  auto mark = [&](const PixelRect& r_in) {
    const PixelRect r = r_in.Intersection(clip);
    if (r.Empty()) return;
    for (int by = r.y0 / block_size; by <= (r.y1 - 1) / block_size; ++by) {
      for (int bx = r.x0 / block_size; bx <= (r.x1 - 1) / block_size; ++bx) {
        on[static_cast<size_t>(by - by0) * nx + (bx - bx0)] = 1;
      }
    }
  };
  if (camera.HasDistortion()) {
    Eigen::AlignedBox3d all;
    for (const auto& box : boxes) all.extend(box);
    if (const auto rect = ProjectBox(all, camera, cam_from_world, margin_px)) mark(*rect);
  } else {
    for (const auto& box : boxes) {
      if (const auto rect = ProjectBox(box, camera, cam_from_world, margin_px)) mark(*rect);
    }
  }
  for (int by = 0; by < ny; ++by) {
    for (int bx = 0; bx < nx; ++bx) {
      if (!on[static_cast<size_t>(by) * nx + bx]) continue;
      const PixelRect block{(bx0 + bx) * block_size, (by0 + by) * block_size, (bx0 + bx + 1) * block_size,
                            (by0 + by + 1) * block_size};
      blocks.push_back(block.Intersection(clip));
    }
  }
  return blocks;
}

Eigen::AlignedBox3d FacesBoundingBox(const Tessellation& tessellation,
                                     const std::vector<int>& faces) {
  Eigen::AlignedBox3d box;
  for (const int f : faces) {
    if (f < 0 || f >= tessellation.NumFaces()) {
      throw std::out_of_range("FacesBoundingBox: face " + std::to_string(f) +
                              " out of range");
    }
    for (int k = 0; k < kSubTrianglesPerFace; ++k) {
      const Eigen::Vector3i& t = tessellation.triangles[f * kSubTrianglesPerFace + k];
      for (int c = 0; c < 3; ++c) box.extend(tessellation.points[t[c]]);
    }
  }
  return box;
}

FaceBvh::FaceBvh(const Tessellation& tessellation) {
  const int num_faces = tessellation.NumFaces();
  face_boxes_.resize(num_faces);
  for (int f = 0; f < num_faces; ++f) face_boxes_[f] = FacesBoundingBox(tessellation, {f});
  order_.resize(num_faces);
  for (int f = 0; f < num_faces; ++f) order_[f] = f;
  nodes_.reserve(2 * static_cast<size_t>(num_faces));
  if (num_faces > 0) Build(0, num_faces);
}

int FaceBvh::Build(int first, int count) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Eigen::AlignedBox3d box;
  for (int i = first; i < first + count; ++i) box.extend(face_boxes_[order_[i]]);
  nodes_[index].box = box;
  constexpr int kLeafSize = 4;
  if (count <= kLeafSize) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  int axis = 0;
  box.diagonal().maxCoeff(&axis);
  const int middle = first + count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + middle,
                   order_.begin() + first + count, [&](int a, int b) {
                     return face_boxes_[a].center()[axis] < face_boxes_[b].center()[axis];
                   });
  const int left = Build(first, middle - first);
  const int right = Build(middle, first + count - middle);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

std::vector<int> FaceBvh::FacesInBox(const Eigen::AlignedBox3d& box) const {
  std::vector<int> faces;
  if (nodes_.empty() || box.isEmpty()) return faces;
  std::vector<int> stack = {0};
  while (!stack.empty()) {
    const Node& node = nodes_[stack.back()];
    stack.pop_back();
    if (!node.box.intersects(box)) continue;
    if (node.left < 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        if (face_boxes_[order_[i]].intersects(box)) faces.push_back(order_[i]);
      }
    } else {
      stack.push_back(node.left);
      stack.push_back(node.right);
    }
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

}  // namespace facets
