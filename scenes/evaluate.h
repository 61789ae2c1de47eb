// Scoring a reconstructed mesh against a ground-truth scene: the accuracy and
// completeness figures by which reconstructions are compared (see docs/EVALUATION.md).
//
// Accuracy (reconstruction -> truth): the reconstruction is sampled uniformly by area;
// each sample's distance to the truth mesh (exact point-triangle distance, CGAL AABB
// tree) is attributed to the region label of the closest truth face, and split by the
// number of images that see the closest truth point (>= 2 or < 2).
// Completeness (truth -> reconstruction): the truth surface is sampled the same way;
// a sample counts only when at least `min_views` images see it (inside the image, not
// occluded: Embree first hit within a tolerance of the sample, not grazing); the share
// of those samples whose distance to the reconstruction is within 0.5, 1, 2 GSD.
// Both are restricted to the region of interest when one is given.
//
// All distances are in metres (local object coordinates) and also in GSD units
// (metres / ground_pixel_size).
#pragma once

#include <Eigen/Core>
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "io/image_block.h"
#include "io/ply_io.h"
#include "refine/facet_crossings.h"

namespace facets {

// The truth written by `facets render`: DIR/truth.ply (faces labelled 0 ground, 1 roof,
// 2 wall, 3 object), DIR/truth.json ("ground_pixel_size" in m, optional
// "region_of_interest" {"min":[x,y,z],"max":[x,y,z]}, optional "labels"
// {"0":"ground",...}) and DIR/sparse/ (COLMAP text model of the cameras).
// A building of the truth scene (truth.json "shapes", type "building"): enough to find
// its walls again. Walls: 0 +u, 1 +v, 2 -u, 3 -v in the frame rotated by azimuth.
struct TruthBuilding {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double azimuth_deg = 0, length = 0, width = 0, height = 0;
  Eigen::Vector4d wall_lean_deg = Eigen::Vector4d::Zero();  // outward, per wall
};

struct TruthScene {
  MeshData mesh;                       // face_labels empty = every face label 0
  double ground_pixel_size = 0.0;      // GSD, m
  std::optional<RegionOfInterest> roi;
  std::map<int, std::string> labels;   // region label -> name
  ImageBlock block;                    // the cameras that photographed the truth
  std::vector<TruthBuilding> buildings;  // from truth.json when it lists shapes
};

// Throws std::runtime_error naming the file and what is wrong.
TruthScene ReadTruthScene(const std::string& dir);

struct EvaluationOptions {
  // Sample spacing on both surfaces, in GSD. A third of a pixel footprint resolves
  // every detail the images could resolve while keeping the sample count bounded.
  double sample_spacing_gsd = 1.0 / 3.0;
  // Upper bound on the samples per surface; when the area would need more, the spacing
  // grows (deterministically) so that a huge scene still evaluates in seconds. The
  // spacing actually used is reported.
  size_t max_samples = 4'000'000;
  // A truth sample is seen by an image when the first hit of the ray from the
  // projection centre lies within this distance (GSD) of the sample. Samples lie on the
  // truth exactly, so this only absorbs Embree's float rounding and the ambiguity at a
  // crease (a wall foot); a quarter pixel cannot hide an occluder the images resolve.
  double visibility_tolerance_gsd = 0.25;
  // A view whose ray meets the truth face at more than this angle from the face normal
  // does not count: at 80 degrees a pixel footprint is already stretched 5.8 times, and
  // the engine ignores such grazing rays too.
  double max_view_angle_deg = 80.0;
  // Truth samples seen by fewer images are left out of completeness (they are kept in
  // EvaluationReport::truth_samples with their view count).
  int min_views = 1;
  // Completeness thresholds in GSD.
  std::vector<double> completeness_thresholds_gsd = {0.5, 1.0, 2.0};
  // Region of interest overriding the truth's (local coordinates).
  std::optional<RegionOfInterest> roi;
  // Height errors (the seeds' "rms of true height errors"): vertical differences
  // between the highest points of reconstruction and truth on a regular XY grid of
  // this spacing (GSD) inside the ROI shrunk by height_border_gsd (the seeds leave out
  // the window border). 0 = off.
  double height_grid_gsd = 2.0;
  double height_border_gsd = 8.0;
  // Leaning walls: reconstructed vertices within this distance (GSD) of the truth
  // wall's plane belong to it (a vertical reconstruction of a 12 m wall leaning 9
  // degrees stays within 8 GSD of it).
  double wall_band_gsd = 8.0;

  // Throws std::invalid_argument naming the offending option.
  void Check() const;
};

struct DistanceStats {
  size_t count = 0;
  double mean = 0, median = 0, rms = 0, p90 = 0, max = 0;  // metres
};

struct CompletenessStats {
  size_t count = 0;                  // samples seen by enough images
  std::vector<double> within;        // share (0..1) per threshold of the options
};

struct RegionScore {
  int label = 0;  // -1 for the row over all regions
  std::string name;
  DistanceStats accuracy;             // reconstruction samples attributed to the region
  // Of those, the samples whose closest truth point is seen by >= 2 / < 2 images (the
  // same visibility test as completeness, applied to that point).
  DistanceStats accuracy_multi_view, accuracy_few_views;
  CompletenessStats completeness;     // truth samples seen by >= min_views images
  CompletenessStats multi_view;       // of those, seen by >= 2 images
  CompletenessStats few_views;        // of those, seen by < 2 images
};

// One truth sample as used by completeness (every sample inside the ROI).
struct TruthSample {
  Eigen::Vector3d point;
  int label = 0;
  int views = 0;          // images that see it
  double distance = 0.0;  // to the reconstruction, m (computed for every sample)
};

// Vertical differences reconstruction - truth at grid points where both exist.
struct HeightErrors {
  size_t count = 0;
  size_t missing = 0;  // grid points where the reconstruction has no surface
  double rms = 0, mean = 0, min = 0, max = 0;  // metres
  double spacing = 0;  // m
};

// The lean of a leaning truth wall as reconstructed: a plane fitted to the
// reconstruction's vertices near the truth wall (within wall_band_gsd of its plane,
// 1 m in from its side edges, between 15 % and 85 % of the eave height).
struct WallLean {
  int building = 0;  // index into TruthScene::buildings
  int wall = 0;      // 0 +u, 1 +v, 2 -u, 3 -v
  double true_lean_deg = 0;       // from the scene description
  double truth_fit_lean_deg = 0;  // plane fitted to the truth wall's vertices (check)
  double lean_deg = 0;            // plane fitted to the reconstructed vertices; NaN: too few
  int vertices = 0;               // reconstructed vertices used
  double rms = 0;                 // of the fit, m
};

// Reported standard deviations of the reconstruction's vertices (when the mesh carries
// per-vertex sigma and views, as tin.ply and surface.ply do), per truth region of the
// closest truth face and by the number of images that saw the vertex: < 2, 2, >= 3.
struct SigmaByViews {
  int label = 0;
  std::string name;
  std::array<size_t, 3> count = {0, 0, 0};
  std::array<double, 3> median = {0, 0, 0};  // m
  std::array<double, 3> mean = {0, 0, 0};    // m
};

struct EvaluationReport {
  double ground_pixel_size = 0.0;  // m
  HeightErrors heights;
  double sample_spacing = 0.0;     // m, reconstruction samples
  double truth_sample_spacing = 0.0;
  std::vector<double> thresholds_gsd;
  size_t num_images = 0;
  size_t num_reconstruction_samples = 0;  // inside the ROI
  size_t num_truth_samples = 0;           // inside the ROI
  size_t num_truth_samples_seen = 0;      // of those, seen by >= min_views images
  std::optional<RegionOfInterest> roi;
  std::string truth_name, mesh_name;      // for the report header
  std::vector<RegionScore> regions;       // sorted by label, then the "all" row
  std::vector<TruthSample> truth_samples;
  std::vector<WallLean> leaning_walls;  // every truth wall with a nonzero lean
  std::vector<SigmaByViews> sigma_by_views;  // empty when the mesh has no sigma/views
  // Self-intersections of the whole evaluated mesh (CGAL self_intersections, coinciding
  // vertices merged; refine/facet_crossings.h): crossing triangle pairs, and triangles the
  // check had to leave out (degenerate or non-manifold after the merge).
  TriangleCrossings mesh_crossings;

  // The region's row or nullptr (label -1 = all regions). The pointer lives as long as
  // the report, so asking a temporary report does not compile.
  const RegionScore* Region(int label) const&;
  const RegionScore* Region(const std::string& name) const&;
  const RegionScore* Region(int label) const&& = delete;
  const RegionScore* Region(const std::string& name) const&& = delete;
  // A fixed-width table in the style of a Ceres FullReport.
  std::string Table() const;
  // Machine-readable report (without the per-sample list unless asked).
  std::string Json(bool with_samples = false) const;
};

EvaluationReport Evaluate(const TruthScene& truth, const MeshData& reconstruction,
                          const EvaluationOptions& options = {});
// Height errors alone (see EvaluationOptions::height_grid_gsd).
HeightErrors EvaluateHeights(const MeshData& truth, const MeshData& reconstruction,
                             const RegionOfInterest& roi, double spacing, double border);
// ReadTruthScene(truth_dir) + ReadMesh(mesh_path) + Evaluate.
EvaluationReport EvaluateFiles(const std::string& truth_dir, const std::string& mesh_path,
                               const EvaluationOptions& options = {});

// Points sampled uniformly by area at about `spacing` (m): deterministic (a
// low-discrepancy sequence per triangle; counts from the cumulative area, so the total
// is floor(area / spacing^2)). face_of[i] receives the face of sample i when not null;
// face_mask, when not null (one entry per face), limits sampling to the faces marked.
std::vector<Eigen::Vector3d> SampleSurface(const MeshData& mesh, double spacing,
                                           std::vector<int>* face_of = nullptr,
                                           const std::vector<bool>* face_mask = nullptr);

// The leaning walls of the truth's buildings as reconstructed (see WallLean).
std::vector<WallLean> EvaluateLeaningWalls(const TruthScene& truth, const MeshData& reconstruction,
                                           const std::optional<RegionOfInterest>& roi, double band);

// Least-squares plane through points (smallest eigenvector of the scatter matrix).
struct PlaneFit {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit; sign with normal.z() >= 0
                                                       // unless vertical, then arbitrary
  double rms = 0.0;                 // residual distance, m
  double max_abs_residual = 0.0;    // m
  // Angle of the plane away from vertical, degrees: 0 for a vertical wall, 90 for a
  // horizontal plane (asin |normal.z|).
  double tilt_from_vertical_deg = 0.0;
  // Angle of the plane away from horizontal, degrees (90 - tilt_from_vertical_deg).
  double slope_deg = 0.0;
};
// Throws std::invalid_argument for fewer than 3 points or collinear points.
PlaneFit FitPlane(const std::vector<Eigen::Vector3d>& points);

}  // namespace facets
