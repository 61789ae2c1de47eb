#include "engine/search/plane_propagation.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/search/patch_score.h"
#include "mesh/closed_surface.h"
#include "mesh/surface_validity.h"
#include "visibility/embree_scene.h"

namespace facets {
namespace {

struct Plane {
  Eigen::Vector3d point;   // the lending vertex, or the lending face's centroid
  Eigen::Vector3d normal;  // unit
};

// The vertex state the iterations read and write (Jacobi: each iteration reads the last).
struct VertexState {
  Eigen::Vector3d position;
  Eigen::Vector3d normal;
  double score = -std::numeric_limits<double>::infinity();
};

class PlaneScorer {
 public:
  PlaneScorer(const TriangleScene& scene, const std::vector<LevelImage>& images,
              const std::vector<Eigen::Vector3d>& centres, double ground_pixel,
              const PlanePropagationOptions& options)
      : scene_(scene), images_(images), centres_(centres), options_(options),
        spacing_(options.sample_pixels * ground_pixel),
        patch_radius_(options.patch_half * options.sample_pixels * ground_pixel),
        scorer_(seeing_, options.min_contrast, options.min_images) {}
  PlaneScorer(const PlaneScorer&) = delete;  // scorer_ refers to seeing_
  PlaneScorer& operator=(const PlaneScorer&) = delete;

  // Mean pairwise NCC of a patch at `p` in the plane normal to `normal`, over the images
  // that see that plane from its front, hold the whole patch in their frame and whose
  // rays to `p` are free up to `slack` (m) before it (the surface a vertex leaves may
  // stand in its way).
  double Score(const Eigen::Vector3d& p, const Eigen::Vector3d& normal, double slack) {
    FindSeeing(p, normal, slack);
    if (static_cast<int>(seeing_.size()) < options_.min_images) return -std::numeric_limits<double>::infinity();
    samples_ = PatchOffsets(normal, options_.patch_half, spacing_);
    for (Eigen::Vector3d& sample : samples_) sample += p;
    return scorer_.Score(samples_);
  }

 private:
  // The images that see the plane (normal n) at `p` from its front at |cos| >= min_cos,
  // hold the patch there, with their rays free up to `slack` before `p`. An image whose
  // frame cuts the patch is left out rather than spoiling the score: the scorer gives no
  // score when one image lacks a sample, and with a dozen images around, one of them
  // mostly does (on the block's first gable 80 % of the vertices had no score of their
  // own, so any neighbour's plane scoring 0.4 was taken).
  void FindSeeing(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double slack) {
    seeing_.clear();
    const double tolerance = slack + patch_radius_;
    for (size_t k = 0; k < images_.size(); ++k) {
      const Eigen::Vector3d d = p - centres_[k];
      const double length = d.norm();
      if (!(-n.dot(d) >= options_.min_cos * length)) continue;
      if (!(length > tolerance)) continue;
      if (!ImageHoldsPatch(images_[k], p, n, patch_radius_)) continue;
      const RayHit hit = scene_.Intersect(centres_[k], d, 0.0f, static_cast<float>(1.0 - tolerance / length));
      if (!hit.hit) seeing_.push_back(&images_[k]);
    }
  }

  const TriangleScene& scene_;
  const std::vector<LevelImage>& images_;
  const std::vector<Eigen::Vector3d>& centres_;
  const PlanePropagationOptions& options_;
  double spacing_;
  double patch_radius_;
  std::vector<const LevelImage*> seeing_;
  std::vector<Eigen::Vector3d> samples_;
  PatchScorer scorer_;  // over seeing_
};

// Planes alike enough that scoring both is wasted: normals within ~8 deg and the
// second's point within a quarter pixel of the first plane.
bool SamePlane(const Plane& a, const Plane& b, double quarter_pixel) {
  return a.normal.dot(b.normal) > 0.99 && std::abs((b.point - a.point).dot(a.normal)) < quarter_pixel;
}

// What every iteration reads.
struct Propagation {
  const TinMesh& mesh;
  const TriangleScene& scene;
  const std::vector<LevelImage>& images;
  const std::vector<Eigen::Vector3d>& centres;  // of the images' projection centres
  const std::vector<Eigen::Vector3d>& points;   // where the vertices started
  const PlanePropagationOptions& options;
  double ground_pixel;
  double max_move;          // m
  std::vector<char> target;  // vertices that may borrow
};

// Vertex v's own plane, then the tangent planes of its neighbours that lend theirs and
// the planes of the faces around its neighbours whose three corners all lend; planes
// from behind and near repeats left out.
void CollectPlanes(const Propagation& run, const std::vector<VertexState>& state, size_t v,
                   std::vector<Plane>* planes) {
  const VertexState& here = state[v];
  auto lends = [&](int w) { return state[w].score >= run.options.source_score; };
  planes->assign(1, {here.position, here.normal});  // its own: not scored again
  auto add = [&](const Plane& plane) {
    if (plane.normal.dot(here.normal) <= 0.0) return;  // the other side
    for (const Plane& other : *planes) {
      if (SamePlane(other, plane, 0.25 * run.ground_pixel)) return;
    }
    planes->push_back(plane);
  };
  for (auto wh : run.mesh.vv_range(run.mesh.vertex_handle(static_cast<int>(v)))) {
    const int w = wh.idx();
    if (lends(w)) add({state[w].position, state[w].normal});
    for (auto f : run.mesh.vf_range(wh)) {
      Eigen::Vector3d corner[3];
      int k = 0;
      bool all = true;
      for (auto c : run.mesh.fv_range(f)) {
        all = all && c.idx() != static_cast<int>(v) && lends(c.idx());
        corner[k++] = state[c.idx()].position;
      }
      if (!all) continue;
      const Eigen::Vector3d normal = (corner[1] - corner[0]).cross(corner[2] - corner[0]);
      if (!(normal.norm() > 0.0)) continue;
      add({(corner[0] + corner[1] + corner[2]) / 3.0, normal.normalized()});
    }
  }
}

// Vertex v tries the planes (after its own): the best one that scores at least min_score
// and min_gain above its own score goes into *next; returns whether one did.
bool TryPlanes(const Propagation& run, const std::vector<Plane>& planes, size_t v, const VertexState& here,
               PlaneScorer* scorer, VertexState* next, int* tried) {
  const PlanePropagationOptions& options = run.options;
  double best = std::max(here.score, -1.0) + options.min_gain;
  best = std::max(best, options.min_score);
  bool changed = false;
  for (size_t k = 1; k < planes.size(); ++k) {
    const Plane& plane = planes[k];
    const Eigen::Vector3d onto = here.position - (here.position - plane.point).dot(plane.normal) * plane.normal;
    const double move = (onto - run.points[v]).norm();
    if (move > run.max_move) continue;
    ++*tried;
    const double score =
        scorer->Score(onto, plane.normal, std::max(move, options.occluder_slack_pixels * run.ground_pixel));
    if (!(score >= best)) continue;
    best = score;
    *next = {onto, plane.normal, score};
    changed = true;
  }
  return changed;
}

// One Jacobi iteration: the vertices a changed neighbour asks to look again try the
// planes around them; *state becomes the new state. Returns the vertices that changed.
int PropagateOnce(const Propagation& run, std::vector<VertexState>* state, std::vector<char>* changed,
                  std::vector<char>* moved, std::vector<int>* tried) {
  const size_t n = state->size();
  std::vector<VertexState> next = *state;
  std::vector<char> look(n, 0);
  for (size_t v = 0; v < n; ++v) {
    if (!(*changed)[v]) continue;
    look[v] = 1;
    for (auto w : run.mesh.vv_range(run.mesh.vertex_handle(static_cast<int>(v)))) look[w.idx()] = 1;
  }
  std::fill(changed->begin(), changed->end(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 32), [&](const tbb::blocked_range<size_t>& r) {
    PlaneScorer scorer(run.scene, run.images, run.centres, run.ground_pixel, run.options);
    std::vector<Plane> planes;
    for (size_t v = r.begin(); v != r.end(); ++v) {
      if (!run.target[v] || !look[v]) continue;
      CollectPlanes(run, *state, v, &planes);
      if (TryPlanes(run, planes, v, (*state)[v], &scorer, &next[v], &(*tried)[v])) (*changed)[v] = 1;
    }
  });
  int changes = 0;
  for (size_t v = 0; v < n; ++v) {
    changes += (*changed)[v];
    (*moved)[v] = (*moved)[v] || (*changed)[v];
  }
  *state = std::move(next);
  return changes;
}

}  // namespace

PlanePropagationReport PropagatePlanes(TinMesh* mesh, const std::vector<LevelImage>& images, double ground_pixel,
                                       const PlanePropagationOptions& options) {
  PlanePropagationReport report;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> triangles;
  TinPointsAndTriangles(*mesh, &points, &triangles);
  if (triangles.empty() || images.size() < 2) return report;
  const TriangleScene scene(EmbreeDevice::Shared(), points, triangles);
  std::vector<Eigen::Vector3d> centres;
  for (const LevelImage& image : images) centres.push_back(image.cam_from_world.Inverse().translation);
  const size_t n = points.size();
  Propagation run{*mesh, scene, images, centres, points, options, ground_pixel,
                  options.max_move_pixels * ground_pixel, std::vector<char>(n, 0)};
  // Where each vertex is, how well its images agree there.
  std::vector<VertexState> state(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
    PlaneScorer scorer(scene, images, centres, ground_pixel, options);
    for (size_t v = r.begin(); v != r.end(); ++v) {
      const auto vh = mesh->vertex_handle(static_cast<int>(v));
      state[v].position = points[v];
      state[v].normal = ToEigen(mesh->normal(vh));
      state[v].score = scorer.Score(points[v], state[v].normal, 0.0);
    }
  });
  const double max_target_nz = std::cos(options.min_target_tilt_deg * M_PI / 180.0);
  for (size_t v = 0; v < n; ++v) {
    report.sources += state[v].score >= options.source_score;
    run.target[v] = !mesh->is_boundary(mesh->vertex_handle(static_cast<int>(v))) &&
                    std::abs(state[v].normal.z()) <= max_target_nz + 1e-12;
    report.targets += run.target[v];
  }
  std::vector<char> moved(n, 0);
  std::vector<int> tried(n, 0);
  // A vertex looks again only when a neighbour changed in the last iteration.
  std::vector<char> changed(n, 1);
  for (int iteration = 0; iteration < options.iterations; ++iteration) {
    if (PropagateOnce(run, &state, &changed, &moved, &tried) == 0) break;
    report.iterations = iteration + 1;
  }
  for (size_t v = 0; v < n; ++v) {
    report.hypotheses += tried[v];
    if (moved[v]) mesh->set_point(mesh->vertex_handle(static_cast<int>(v)), ToOpenMesh(state[v].position));
  }
  CopyStepFields(GuardAndMeasureStep(mesh, points, 0.05 * ground_pixel), &report);
  return report;
}

}  // namespace facets
