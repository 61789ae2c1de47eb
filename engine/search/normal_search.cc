#include "engine/search/normal_search.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "engine/search/patch_score.h"
#include "mesh/closed_surface.h"
#include "mesh/surface_validity.h"
#include "visibility/embree_scene.h"

namespace facets {
namespace {

struct Candidate {
  double offset = 0.0;  // along the normal (m)
  bool peak = false;
};

// Whether the image holds every sample the search can ask of it: the patch at both ends
// of the range and where the vertex is. An image that sees a vertex near its frame would
// otherwise spoil every offset's score.
bool HoldsSearchBox(const LevelImage& image, const Eigen::Vector3d& p, const Eigen::Vector3d& normal,
                    double range, double patch_radius) {
  for (double offset : {-range, 0.0, range}) {
    if (!ImageHoldsPatch(image, p + offset * normal, normal, patch_radius)) return false;
  }
  return true;
}

// The scores of offsets along one direction, the patch in the plane normal to it.
struct Scan {
  double here = -std::numeric_limits<double>::infinity();  // at offset 0
  double best = -std::numeric_limits<double>::infinity();  // at the peak (when peak)
  double offset = 0.0;  // of the peak along the direction (m)
  bool peak = false;    // an interior maximum of at least min_score
};

Scan ScanAlong(const Eigen::Vector3d& p, const Eigen::Vector3d& direction, const std::vector<const LevelImage*>& images,
               double ground_pixel, const NormalSearchOptions& options) {
  Scan result;
  const std::vector<Eigen::Vector3d> patch =
      PatchOffsets(direction, options.patch_half, options.sample_pixels * ground_pixel);
  const int steps = static_cast<int>(std::floor(options.range_pixels / options.step_pixels));
  const double step = options.step_pixels * ground_pixel;
  PatchScorer search(images, options.min_contrast, options.min_images);
  std::vector<double> score(2 * steps + 1);
  std::vector<Eigen::Vector3d> samples(patch.size());
  for (int k = -steps; k <= steps; ++k) {
    const Eigen::Vector3d centre = p + k * step * direction;
    for (size_t s = 0; s < patch.size(); ++s) samples[s] = centre + patch[s];
    score[k + steps] = search.Score(samples);
  }
  result.here = score[steps];
  const int best = static_cast<int>(std::max_element(score.begin(), score.end()) - score.begin());
  // A peak at the end of the range may lie beyond it: not taken.
  if (best == 0 || best == 2 * steps || best == steps) return result;
  if (!(score[best] >= options.min_score)) return result;
  // Parabola through the peak and its neighbours for the sub-step offset.
  const double a = score[best - 1], b = score[best], c = score[best + 1];
  double frac = 0.0;
  if (std::isfinite(a) && std::isfinite(c) && a - 2 * b + c < 0) frac = 0.5 * (a - c) / (a - 2 * b + c);
  result.offset = (best - steps + std::clamp(frac, -0.5, 0.5)) * step;
  result.best = score[best];
  result.peak = true;
  return result;
}

// What the search of every vertex reads.
struct SearchContext {
  const TinMesh& mesh;
  const std::vector<LevelImage>& images;
  const std::vector<Eigen::Vector3d>& points;
  const std::vector<Eigen::Vector3d>& centres;  // of the images' projection centres
  const TriangleScene& scene;
  const NormalSearchOptions& options;
  double ground_pixel;
  double range;         // of the offsets (m)
  double patch_radius;  // m
  // Rays blocked no closer than this to the vertex count as seeing it: the surface
  // around a vertex that is off by up to the range may stand in its own way.
  double tolerance;
  double max_cos_to_views;  // cos of NormalSearchOptions::min_angle_to_views_deg
};

// The images whose rays to p are free up to the tolerance before it.
void FindVisible(const SearchContext& s, const Eigen::Vector3d& p, std::vector<size_t>* visible) {
  visible->clear();
  for (size_t k = 0; k < s.images.size(); ++k) {
    const Eigen::Vector3d d = p - s.centres[k];
    const double length = d.norm();
    if (!(length > s.tolerance)) continue;
    const RayHit hit = s.scene.Intersect(s.centres[k], d, 0.0f, static_cast<float>(1.0 - s.tolerance / length));
    if (!hit.hit) visible->push_back(k);
  }
}

// Of the visible images, those that see the plane through p with this normal and hold the
// search box along it; whether they are at least min_images.
bool FindSeeing(const SearchContext& s, const Eigen::Vector3d& p, const Eigen::Vector3d& normal,
                const std::vector<size_t>& visible, std::vector<const LevelImage*>* seeing) {
  seeing->clear();
  for (size_t k : visible) {
    const Eigen::Vector3d d = p - s.centres[k];
    if (-normal.dot(d) < s.options.min_cos * d.norm()) continue;
    if (!HoldsSearchBox(s.images[k], p, normal, s.range, s.patch_radius)) continue;
    seeing->push_back(&s.images[k]);
  }
  return static_cast<int>(seeing->size()) >= s.options.min_images;
}

// Searches vertex v along its normal; returns whether it was searched (steep to the
// images that see it), *candidate: its accepted peak, if any.
bool SearchVertex(const SearchContext& s, size_t v, std::vector<size_t>* visible,
                  std::vector<const LevelImage*>* seeing, Candidate* candidate) {
  const NormalSearchOptions& options = s.options;
  const auto vh = s.mesh.vertex_handle(static_cast<int>(v));
  if (s.mesh.is_boundary(vh)) return false;
  const Eigen::Vector3d& p = s.points[v];
  const Eigen::Vector3d normal = ToEigen(s.mesh.normal(vh));
  FindVisible(s, p, visible);
  // Only a vertex steep to its images (a wall) is searched.
  if (!FindSeeing(s, p, normal, *visible, seeing)) return false;
  if (options.min_angle_to_views_deg > 0.0) {
    Eigen::Vector3d towards = Eigen::Vector3d::Zero();
    for (const LevelImage* image : *seeing) towards += (s.centres[image - s.images.data()] - p).normalized();
    const bool steep = towards.normalized().dot(normal) <= s.max_cos_to_views;
    if (!steep) return false;
  }
  // The score where the vertex is (offset 0, the patch in its own tangent plane) is
  // what a peak must beat by min_gain.
  const Scan scan = ScanAlong(p, normal, *seeing, s.ground_pixel, options);
  const double here = scan.here;
  if (!scan.peak) return true;
  if (std::isfinite(here) && scan.best - here < options.min_gain) return true;
  candidate->offset = scan.offset;
  candidate->peak = true;
  return true;
}

// Median of the candidate moves over the vertex and its neighbours that face the same
// way (no peak counts as no move): a lone false peak is outvoted. Counts the searched
// vertices and peaks into *report.
std::vector<Eigen::Vector3d> MedianMoves(const TinMesh& mesh, const std::vector<Candidate>& candidates,
                                         const std::vector<char>& searched, const NormalSearchOptions& options,
                                         NormalSearchReport* report) {
  const size_t n = candidates.size();
  std::vector<Eigen::Vector3d> moves(n, Eigen::Vector3d::Zero());
  for (size_t v = 0; v < n; ++v) {
    report->searched += searched[v];
    report->peaks += candidates[v].peak;
    if (!candidates[v].peak) continue;
    const auto vh = mesh.vertex_handle(static_cast<int>(v));
    const Eigen::Vector3d normal = ToEigen(mesh.normal(vh));
    std::vector<const Candidate*> around = {&candidates[v]};
    for (auto vv : mesh.vv_range(vh)) {
      if (ToEigen(mesh.normal(vv)).dot(normal) < options.neighbour_cos) continue;
      around.push_back(searched[vv.idx()] ? &candidates[vv.idx()] : &candidates[v]);
    }
    const size_t middle = around.size() / 2;
    std::vector<double> values;
    for (const Candidate* c : around) values.push_back(c->offset);
    std::nth_element(values.begin(), values.begin() + middle, values.end());
    moves[v] = values[middle] * normal;
  }
  return moves;
}

}  // namespace

NormalSearchReport SearchAlongNormals(TinMesh* mesh, const std::vector<LevelImage>& images,
                                      double ground_pixel, const NormalSearchOptions& options) {
  NormalSearchReport report;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  TinPointsAndTriangles(*mesh, &points, &triangles);
  if (triangles.empty() || images.empty()) return report;
  const TriangleScene scene(EmbreeDevice::Shared(), points, triangles);
  std::vector<Eigen::Vector3d> centres;
  for (const LevelImage& image : images) centres.push_back(image.cam_from_world.Inverse().translation);
  const double range = options.range_pixels * ground_pixel;
  const double patch_radius = options.patch_half * options.sample_pixels * ground_pixel;
  const SearchContext context{*mesh, images, points, centres, scene, options, ground_pixel, range, patch_radius,
                              range + patch_radius, std::cos(options.min_angle_to_views_deg * M_PI / 180.0)};
  const size_t n = points.size();
  std::vector<Candidate> candidates(n);
  std::vector<char> searched(n, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<size_t> visible;  // images whose ray to the vertex is free
    std::vector<const LevelImage*> seeing;
    for (size_t v = r.begin(); v != r.end(); ++v) {
      searched[v] = SearchVertex(context, v, &visible, &seeing, &candidates[v]) ? 1 : 0;
    }
  });
  const std::vector<Eigen::Vector3d> moves = MedianMoves(*mesh, candidates, searched, options, &report);
  const std::vector<Eigen::Vector3d> before = points;
  const double least = 0.1 * options.step_pixels * ground_pixel;
  for (size_t v = 0; v < n; ++v) {
    if (moves[v].norm() < least) continue;
    mesh->set_point(mesh->vertex_handle(static_cast<int>(v)), ToOpenMesh(points[v] + moves[v]));
  }
  CopyStepFields(GuardAndMeasureStep(mesh, before, least), &report);
  return report;
}

}  // namespace facets
