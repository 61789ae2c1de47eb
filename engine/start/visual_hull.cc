#include "engine/start/visual_hull.h"

#include <CGAL/Complex_2_in_triangulation_3.h>
#include <CGAL/IO/facets_in_complex_2_to_triangle_mesh.h>
#include <CGAL/Implicit_surface_3.h>
#include <CGAL/Random.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_default_triangulation_3.h>
#include <CGAL/make_surface_mesh.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "io/image_io.h"

namespace facets {

ForegroundOptions VisualHullOptions::DefaultForeground() {
  ForegroundOptions f;
  f.background_max = 15.0;
  f.open_radius = 1;
  f.largest_component = true;
  f.fill_holes_below = 500;
  return f;
}

void VisualHullOptions::Check() const {
  foreground.Check();
  if (!(voxel_size >= 0.0)) throw std::invalid_argument("visual hull: voxel size must be >= 0");
  if (allowed_misses < 0) throw std::invalid_argument("visual hull: allowed misses must be >= 0");
}

long long VisualHullGrid::Count() const {
  long long n = 0;
  for (uint8_t v : inside) n += v ? 1 : 0;
  return n;
}

Eigen::Vector3d VisualHullGrid::Centroid() const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  long long n = 0;
  for (int k = 0; k < size.z(); ++k) {
    for (int j = 0; j < size.y(); ++j) {
      for (int i = 0; i < size.x(); ++i) {
        if (inside[Index(i, j, k)]) {
          sum += Centre(i, j, k);
          ++n;
        }
      }
    }
  }
  return n > 0 ? Eigen::Vector3d(sum / static_cast<double>(n)) : origin;
}

namespace {

// Keeps the largest 6-connected component of inside voxels.
void KeepLargestComponent(VisualHullGrid* grid) {
  std::vector<int> label(grid->inside.size(), 0);
  std::vector<long long> sizes(1, 0);
  std::vector<size_t> stack;
  const int nx = grid->size.x(), ny = grid->size.y(), nz = grid->size.z();
  for (size_t start = 0; start < grid->inside.size(); ++start) {
    if (!grid->inside[start] || label[start]) continue;
    const int id = static_cast<int>(sizes.size());
    long long count = 0;
    label[start] = id;
    stack.assign(1, start);
    while (!stack.empty()) {
      const size_t p = stack.back();
      stack.pop_back();
      ++count;
      const int i = static_cast<int>(p % nx);
      const int j = static_cast<int>((p / nx) % ny);
      const int k = static_cast<int>(p / (static_cast<size_t>(nx) * ny));
      const int di[6] = {-1, 1, 0, 0, 0, 0}, dj[6] = {0, 0, -1, 1, 0, 0}, dk[6] = {0, 0, 0, 0, -1, 1};
      for (int n = 0; n < 6; ++n) {
        const int a = i + di[n], b = j + dj[n], c = k + dk[n];
        if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
        const size_t q = grid->Index(a, b, c);
        if (grid->inside[q] && !label[q]) {
          label[q] = id;
          stack.push_back(q);
        }
      }
    }
    sizes.push_back(count);
  }
  const int best = static_cast<int>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
  for (size_t p = 0; p < label.size(); ++p) grid->inside[p] = label[p] == best && best > 0 ? 1 : 0;
}

}  // namespace

Eigen::Vector3i VisualHullGridSize(const Eigen::AlignedBox3d& box, double voxel) {
  Eigen::Vector3i size;
  for (int a = 0; a < 3; ++a) size[a] = std::max(1, static_cast<int>(std::ceil(box.sizes()[a] / voxel)));
  return size;
}

VisualHullGrid CarveVisualHull(const std::vector<Camera>& cameras,
                               const std::vector<Rigid3d>& cam_from_world,
                               const std::vector<PixelMask>& masks,
                               const Eigen::AlignedBox3d& box, const VisualHullOptions& options) {
  options.Check();
  if (cameras.size() != masks.size() || cam_from_world.size() != masks.size() || masks.empty()) {
    throw std::invalid_argument("visual hull: one camera, pose and mask per image needed");
  }
  if (box.isEmpty() || !(box.sizes().minCoeff() > 0.0)) {
    throw std::invalid_argument("visual hull: the box is empty");
  }
  VisualHullGrid grid;
  grid.voxel = options.voxel_size > 0.0 ? options.voxel_size : box.sizes().maxCoeff() / 200.0;
  grid.size = VisualHullGridSize(box, grid.voxel);
  const long long total = static_cast<long long>(grid.size.x()) * grid.size.y() * grid.size.z();
  if (total > 400LL * 1000 * 1000) {
    throw std::invalid_argument("visual hull: more than 400 million voxels; give a larger voxel");
  }
  grid.origin = box.min() + 0.5 * grid.voxel * Eigen::Vector3d::Ones();
  grid.inside.assign(static_cast<size_t>(total), 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.size.z()), [&](const auto& slices) {
    for (int k = slices.begin(); k != slices.end(); ++k) {
      for (int j = 0; j < grid.size.y(); ++j) {
        for (int i = 0; i < grid.size.x(); ++i) {
          const Eigen::Vector3d x = grid.Centre(i, j, k);
          int misses = 0;
          for (size_t m = 0; m < masks.size() && misses <= options.allowed_misses; ++m) {
            const Eigen::Vector3d c = cam_from_world[m] * x;
            bool foreground = false;
            if (c.z() > 0.0) {
              const Eigen::Vector2d p = cameras[m].ImageFromCam(c);
              const int px = static_cast<int>(std::floor(p.x()));
              const int py = static_cast<int>(std::floor(p.y()));
              foreground = px >= 0 && py >= 0 && px < masks[m].width && py < masks[m].height &&
                           masks[m].at(px, py) != 0;
            }
            misses += foreground ? 0 : 1;
          }
          grid.inside[grid.Index(i, j, k)] = misses <= options.allowed_misses ? 1 : 0;
        }
      }
    }
  });
  KeepLargestComponent(&grid);
  return grid;
}

namespace {

long long VoxelCount(const Eigen::AlignedBox3d& box, double voxel) {
  const Eigen::Vector3d size = (box.sizes() / voxel).array().ceil().max(1.0);
  return static_cast<long long>(size.prod());
}

std::string GridText(const Eigen::AlignedBox3d& box, double voxel) {
  const Eigen::Vector3i size = VisualHullGridSize(box, voxel);
  std::ostringstream out;
  out << size.x() << " x " << size.y() << " x " << size.z() << " = " << VoxelCount(box, voxel) << " voxels";
  return out.str();
}

}  // namespace

ConstraintVoxelChoice ChooseConstraintVoxel(const ImageBlock& block, const Eigen::AlignedBox3d& box,
                                            double given, double start_voxel) {
  ConstraintVoxelChoice choice;
  choice.footprint = GroundPixel(block, box.center());
  std::ostringstream why;
  why << "pixel footprint " << choice.footprint << " m at the box's centre (median over " << block.images.size()
      << " images of distance / focal length)";
  if (given > 0.0) {
    choice.voxel = given;
    choice.voxels = VoxelCount(box, given);
    why << "; voxel " << given << " m given: " << GridText(box, given);
    choice.why = why.str();
    return choice;
  }
  double voxel = kConstraintVoxelFootprints * choice.footprint;
  why << "; " << kConstraintVoxelFootprints << " footprint";
  if (!(voxel > 0.0) || VoxelCount(box, voxel) > kMaxConstraintVoxels) {
    voxel = std::cbrt(box.volume() / static_cast<double>(kMaxConstraintVoxels));
    while (VoxelCount(box, voxel) > kMaxConstraintVoxels) voxel *= 1.001;
    why << " needs more than " << kMaxConstraintVoxels << " voxels, so " << voxel << " m";
  } else {
    why << " " << voxel << " m";
  }
  if (!(voxel < start_voxel)) {
    why << ", not finer than the start's " << start_voxel << " m voxels: the start's hull";
    choice.why = why.str();
    return choice;
  }
  choice.voxel = voxel;
  choice.voxels = VoxelCount(box, voxel);
  why << ": " << GridText(box, voxel) << " (at most " << kMaxConstraintVoxels << ")";
  choice.why = why.str();
  return choice;
}

HullViews ReadHullViews(const ImageBlock& block, const ForegroundOptions& foreground) {
  foreground.Check();
  HullViews views;
  for (const BlockImage& image : block.images) {
    if (image.path.empty()) {
      throw std::runtime_error("visual hull: image " + image.name + " has no file");
    }
    const Camera& camera = block.CameraOf(image);
    try {
      views.masks.push_back(ForegroundMask(ReadImageFor(image.path, camera), foreground));
    } catch (const std::exception& e) {
      throw std::runtime_error("visual hull: " + image.path + ": " + e.what());
    }
    views.cameras.push_back(camera);
    views.cam_from_world.push_back(image.cam_from_world);
  }
  return views;
}

VisualHullGrid CarveVisualHull(const ImageBlock& block, const Eigen::AlignedBox3d& box,
                               const VisualHullOptions& options) {
  options.Check();
  const HullViews views = ReadHullViews(block, options.foreground);
  return CarveVisualHull(views.cameras, views.cam_from_world, views.masks, box, options);
}

namespace {

using Tr = CGAL::Surface_mesh_default_triangulation_3;
using C2t3 = CGAL::Complex_2_in_triangulation_3<Tr>;
using GT = Tr::Geom_traits;
using Point3 = GT::Point_3;
using FT = GT::FT;

// 1/2 - the smoothed occupancy: negative inside.
struct OccupancyFunction {
  const HullOccupancy* occupancy;
  FT operator()(const Point3& p) const {
    return FT(0.5 - occupancy->At(Eigen::Vector3d(CGAL::to_double(p.x()), CGAL::to_double(p.y()),
                                                  CGAL::to_double(p.z()))));
  }
};

}  // namespace

HullOccupancy SmoothHullOccupancy(const VisualHullGrid& grid) {
  HullOccupancy h;
  h.grid = &grid;
  h.smooth.assign(grid.inside.size(), 0.0f);
  const int nx = grid.size.x(), ny = grid.size.y(), nz = grid.size.z();
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        int sum = 0;
        for (int c = -1; c <= 1; ++c) {
          for (int b = -1; b <= 1; ++b) {
            for (int a = -1; a <= 1; ++a) sum += grid.Inside(i + a, j + b, k + c) ? 1 : 0;
          }
        }
        h.smooth[grid.Index(i, j, k)] = static_cast<float>(sum) / 27.0f;
      }
    }
  }
  return h;
}

double HullOccupancy::At(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d u = (p - grid->origin) / grid->voxel;
  const int i0 = static_cast<int>(std::floor(u.x())), j0 = static_cast<int>(std::floor(u.y())),
            k0 = static_cast<int>(std::floor(u.z()));
  const double fx = u.x() - i0, fy = u.y() - j0, fz = u.z() - k0;
  double value = 0.0;
  for (int c = 0; c < 8; ++c) {
    const int i = i0 + (c & 1), j = j0 + ((c >> 1) & 1), k = k0 + ((c >> 2) & 1);
    if (i < 0 || j < 0 || k < 0 || i >= grid->size.x() || j >= grid->size.y() ||
        k >= grid->size.z()) {
      continue;
    }
    const double w = ((c & 1) ? fx : 1 - fx) * (((c >> 1) & 1) ? fy : 1 - fy) *
                     (((c >> 2) & 1) ? fz : 1 - fz);
    value += w * smooth[grid->Index(i, j, k)];
  }
  return value;
}

int PullInsideHull(const HullOccupancy& occupancy, const std::vector<Eigen::Vector3d>& directions,
                   double max_move, std::vector<Eigen::Vector3d>* points, int* unresolved) {
  if (directions.size() != points->size()) {
    throw std::invalid_argument("PullInsideHull: one direction per point needed");
  }
  const double step = 0.25 * occupancy.grid->voxel;
  int moved = 0, stuck = 0;
  for (size_t n = 0; n < points->size(); ++n) {
    Eigen::Vector3d& p = (*points)[n];
    if (occupancy.Inside(p)) continue;
    const Eigen::Vector3d d = directions[n].normalized();
    if (!d.allFinite()) {
      ++stuck;
      continue;
    }
    double outside = 0.0, inside = -1.0;
    for (double t = step; t <= max_move + 1e-12; t += step) {
      if (occupancy.Inside(p - t * d)) {
        inside = t;
        break;
      }
      outside = t;
    }
    if (inside < 0.0) {
      ++stuck;
      continue;
    }
    for (int it = 0; it < 8; ++it) {
      const double mid = 0.5 * (outside + inside);
      (occupancy.Inside(p - mid * d) ? inside : outside) = mid;
    }
    p -= inside * d;
    ++moved;
  }
  if (unresolved) *unresolved = stuck;
  return moved;
}

int PushOntoHullRims(const HullOccupancy& occupancy, const HullViews& views,
                     const std::vector<Eigen::Vector3d>& directions, double max_move, double max_cos,
                     std::vector<Eigen::Vector3d>* points) {
  if (directions.size() != points->size()) {
    throw std::invalid_argument("PushOntoHullRims: one direction per point needed");
  }
  if (views.cameras.size() != views.masks.size() || views.cam_from_world.size() != views.masks.size()) {
    throw std::invalid_argument("PushOntoHullRims: one camera, pose and mask per image needed");
  }
  std::vector<Eigen::Vector3d> centres;
  for (const Rigid3d& pose : views.cam_from_world) centres.push_back(pose.Inverse().translation);
  const double voxel = occupancy.grid->voxel;
  const double step = 0.25 * voxel;
  // Background in image m at x: outside the image or behind the camera counts too.
  auto background = [&](size_t m, const Eigen::Vector3d& x) {
    const Eigen::Vector3d c = views.cam_from_world[m] * x;
    if (!(c.z() > 0.0)) return true;
    const Eigen::Vector2d p = views.cameras[m].ImageFromCam(c);
    const int px = static_cast<int>(std::floor(p.x()));
    const int py = static_cast<int>(std::floor(p.y()));
    return !(px >= 0 && py >= 0 && px < views.masks[m].width && py < views.masks[m].height &&
             views.masks[m].at(px, py) != 0);
  };
  std::vector<uint8_t> moved(points->size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points->size()), [&](const auto& range) {
    for (size_t n = range.begin(); n != range.end(); ++n) {
      Eigen::Vector3d& p = (*points)[n];
      if (!occupancy.Inside(p)) continue;
      const Eigen::Vector3d d = directions[n].normalized();
      if (!d.allFinite()) continue;
      double inside = 0.0, outside = -1.0;
      for (double t = step; t <= max_move + 1e-12; t += step) {
        if (!occupancy.Inside(p + t * d)) {
          outside = t;
          break;
        }
        inside = t;
      }
      if (outside < 0.0) continue;
      for (int it = 0; it < 8; ++it) {
        const double mid = 0.5 * (outside + inside);
        (occupancy.Inside(p + mid * d) ? inside : outside) = mid;
      }
      const Eigen::Vector3d boundary = p + inside * d;
      const Eigen::Vector3d beyond = boundary + voxel * d;
      bool rim = false;
      for (size_t m = 0; m < views.masks.size() && !rim; ++m) {
        const Eigen::Vector3d ray = (boundary - centres[m]).normalized();
        rim = std::abs(ray.dot(d)) <= max_cos && background(m, beyond);
      }
      if (!rim) continue;
      p = boundary;
      moved[n] = 1;
    }
  });
  int count = 0;
  for (uint8_t m : moved) count += m;
  return count;
}

void MeshVisualHull(const VisualHullGrid& grid, double edge_length,
                    std::vector<Eigen::Vector3d>* points, std::vector<Eigen::Vector3i>* triangles) {
  if (grid.Count() == 0) throw std::runtime_error("visual hull: no voxel is inside every silhouette");
  if (!(edge_length > 0.0)) throw std::invalid_argument("visual hull: edge length must be > 0");
  // Box-blurred: smooths the voxel staircase the mesher would otherwise follow.
  const HullOccupancy occupancy = SmoothHullOccupancy(grid);
  const int nx = grid.size.x(), ny = grid.size.y(), nz = grid.size.z();
  // The mesher shoots its first rays from the bounding sphere's centre, which must lie
  // inside: the inside voxel of highest blurred occupancy nearest to the centroid.
  const Eigen::Vector3d centroid = grid.Centroid();
  Eigen::Vector3d centre = centroid;
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        if (occupancy.smooth[grid.Index(i, j, k)] < 0.999f) continue;
        const double d = (grid.Centre(i, j, k) - centroid).squaredNorm();
        if (d < best) {
          best = d;
          centre = grid.Centre(i, j, k);
        }
      }
    }
  }
  if (!std::isfinite(best)) throw std::runtime_error("visual hull: no voxel lies deep inside");
  const Eigen::Vector3d far_corner =
      grid.origin + grid.voxel * (grid.size.cast<double>() + Eigen::Vector3d::Ones());
  double radius = 0.0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? far_corner.x() : grid.origin.x() - grid.voxel,
                                 (c & 2) ? far_corner.y() : grid.origin.y() - grid.voxel,
                                 (c & 4) ? far_corner.z() : grid.origin.z() - grid.voxel);
    radius = std::max(radius, (corner - centre).norm());
  }
  Tr tr;
  C2t3 c2t3(tr);
  const OccupancyFunction function{&occupancy};
  const CGAL::Implicit_surface_3<GT, OccupancyFunction> surface(
      function, GT::Sphere_3(Point3(centre.x(), centre.y(), centre.z()), radius * radius),
      FT(0.01 * grid.voxel / radius));
  const CGAL::Surface_mesh_default_criteria_3<Tr> criteria(
      25.0, edge_length / std::sqrt(3.0), std::max(0.15 * edge_length, 0.5 * grid.voxel));
  // The mesher seeds its initial points from CGAL's default random generator, which is
  // seeded from the clock: the same hull gave 1158 or 1204 start faces from run to run.
  CGAL::get_default_random() = CGAL::Random(0);
  CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Manifold_tag(), 40);
  CGAL::Surface_mesh<Point3> mesh;
  CGAL::facets_in_complex_2_to_triangle_mesh(c2t3, mesh);
  if (mesh.number_of_faces() == 0) throw std::runtime_error("visual hull: the mesher found no surface");
  points->clear();
  triangles->clear();
  for (auto v : mesh.vertices()) {
    const Point3& p = mesh.point(v);
    points->emplace_back(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
  }
  double volume = 0.0;
  for (auto f : mesh.faces()) {
    Eigen::Vector3i t;
    int n = 0;
    for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) t[n++] = static_cast<int>(v);
    triangles->push_back(t);
    volume += (*points)[t[0]].dot((*points)[t[1]].cross((*points)[t[2]])) / 6.0;
  }
  if (volume < 0.0) {
    for (Eigen::Vector3i& t : *triangles) std::swap(t[1], t[2]);
  }
}

}  // namespace facets
