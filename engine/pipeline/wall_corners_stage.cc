#include "engine/pipeline/wall_corners_stage.h"

#include <algorithm>
#include <iomanip>
#include <sstream>
#include <utility>
#include <vector>

#include "engine/pipeline/local_readjustment.h"
#include "engine/pipeline/trial.h"
#include "mesh/local_ops.h"
#include "mesh/surface_validity.h"
#include "refine/wall_corners.h"

namespace facets {
namespace {

// The corners' bands grown by this many edge rings: where the stretched edges are split
// before the corners are laid (a band reaches 1.5 edges from its line; the split edges
// are those of the walls' faces beside it).
constexpr int kCornerSplitRings = 3;

std::vector<bool> AroundCorners(const TinMesh& mesh, const WallCornerSearch& search) {
  std::vector<bool> near(mesh.n_vertices(), false);
  for (const WallCorner& corner : search.corners) {
    for (int v : corner.band) near[v] = true;
  }
  return GrowByRings(mesh, std::move(near), kCornerSplitRings);
}

// Splits the stretched edges near the corners at G1 midpoints and adjusts the windows
// around the splits again; a crumpled wall can make triangles cross there: untangled
// around the splits, or the level keeps its triangles. True when edges were split.
bool SplitStretchedEdgesNear(const RunContext& run, LevelPass* pass, const std::vector<bool>& near) {
  TinMesh& mesh = *pass->mesh;
  QualityOptions quality;
  quality.target_edge_length = run.EdgeLength(pass->level);
  quality.max_rounds = 2;
  quality.near = &near;
  if (CountLongEdges(mesh, quality) == 0) return false;
  TinMesh before_split = mesh;
  auto count_crossing = [&run](const TinMesh& surface) {
    const auto clock = run.profile->Part("crossing counts");
    return CountSelfIntersections(surface);
  };
  const int crossing_before = count_crossing(mesh);
  const QualityReport split = QualityPass(&mesh, quality);
  UpdateVertexNormals(&mesh);
  int crossing_after = count_crossing(mesh);
  if (crossing_after > crossing_before && run.options.fold_lips_untangle_rounds > 0) {
    const auto clock = run.profile->Part("untangling");
    const std::vector<bool> movable = TrialNeighbourhood(mesh, before_split);
    crossing_after = UntangleSelfIntersections(&mesh, run.options.fold_lips_untangle_rounds, &movable).pairs_after;
    UpdateVertexNormals(&mesh);
  }
  if (crossing_after > crossing_before) {
    mesh = std::move(before_split);
    run.Say(pass->Prefix() + " corners: splitting the stretched edges made " +
            std::to_string(crossing_after - crossing_before) + " crossing pairs, left");
    return false;
  }
  pass->report.corner_splits = split.splits;
  const auto clock = run.profile->Part("split re-adjustment");
  LocalReadjustment local = ReadjustAroundSplits(
      &mesh, before_split, pass->adjusted, run.options.wall_corners_local_rings, run.images.ForWindows(pass->level),
      pass->adjustment, run.options.windows, pass->Finest(run), run.options.progress);
  run.Say(pass->Prefix() + " corners: " + std::to_string(split.splits) + " stretched edges split near them, " +
          std::to_string(mesh.n_faces()) + " faces; adjusted again in " + std::to_string(local.windows) +
          " local windows");
  pass->adjusted = std::move(local.level);
  return true;
}

WallCornerOptions CornerOptions(const RunContext& run, const LevelPass& pass) {
  WallCornerOptions corner_options;
  corner_options.edge_length = run.EdgeLength(pass.level);
  corner_options.vertical = run.options.wall_corners;
  corner_options.feet = run.options.wall_feet;
  corner_options.eaves = run.options.wall_eaves;
  corner_options.min_corner_angle_deg = run.options.wall_corner_min_angle_deg;
  corner_options.merge_wall_pieces = run.options.wall_merge_pieces;
  return corner_options;
}

std::string FoundLine(const RunContext& run, const LevelPass& pass, const WallCornerSearch& search) {
  const LevelReport& r = pass.report;
  return pass.Prefix() + " corners: " + std::to_string(search.regions) + " planar regions (" +
         std::to_string(search.wall_regions) + " walls" +
         (search.merged_walls > 0 ? ", " + std::to_string(search.merged_walls) + " wall pieces merged" : std::string()) +
         "), " + std::to_string(r.corners_found) + " vertical corners" +
         (run.options.wall_feet ? ", " + std::to_string(r.feet_found) + " feet" : std::string()) +
         (run.options.wall_eaves ? ", " + std::to_string(r.eaves_found) + " eaves" : std::string());
}

std::ostringstream CornerLine(const LevelPass& pass, const WallCorner& corner, const CornerLaying& laid) {
  std::ostringstream line;
  line.precision(3);
  line << std::fixed << pass.Prefix() << ": " << CreaseName(corner.kind) << " at (" << corner.point.x() << ", "
       << corner.point.y() << ", " << corner.point.z() << "), planes " << std::setprecision(1) << corner.angle_deg()
       << std::setprecision(3) << " deg apart, " << laid.moved << " vertices (" << laid.on_line
       << " onto the line), max move " << laid.max_move << " m";
  return line;
}

// One crease laid and judged; *faults are the TIN's before it, updated when it is kept.
void TryCorner(const RunContext& run, LevelPass* pass, const WallCorner& corner, const WallCornerOptions& corner_options,
               SurfaceFaults* faults) {
  TinMesh& mesh = *pass->mesh;
  TinMesh before = mesh;
  const CornerLaying laid = LayCornerOntoWalls(&mesh, corner, corner_options);
  if (laid.moved == 0) return;
  UpdateVertexNormals(&mesh);
  std::ostringstream line = CornerLine(*pass, corner, laid);
  const SurfaceFaults now = UntangleNewFaults(run, &mesh, before, *faults, run.options.fold_lips_untangle_rounds);
  if (now.WorseThan(*faults)) {
    line << ": " << now.crossing - faults->crossing << " crossing pairs and " << now.folded - faults->folded
         << " folded faces, left";
    run.Say(line.str());
    mesh = std::move(before);
    ++pass->report.corners_dropped;
    return;
  }
  const TrialVerdict verdict =
      JudgeProposal(run, pass, std::move(before), run.options.wall_corners_local_rings, run.options.wall_corners_tolerance);
  line << "; sigma0 " << verdict.now_sigma0 << " against " << verdict.was_sigma0 << " (" << verdict.local_windows
       << " local windows), " << (verdict.kept ? "kept" : "dropped");
  run.Say(line.str());
  if (!verdict.kept) {
    ++pass->report.corners_dropped;
    return;
  }
  LevelReport& r = pass->report;
  ++(corner.kind == CreaseKind::kFoot ? r.feet_laid : corner.kind == CreaseKind::kEave ? r.eaves_laid : r.corners_laid);
  r.corner_vertices_moved += laid.moved;
  *faults = CountSurfaceFaults(run, mesh);
}

}  // namespace

void LayWallCorners(const RunContext& run, LevelPass* pass) {
  const WallCornerOptions corner_options = CornerOptions(run, *pass);
  // The creases of the level as it stands say where its stretched edges are split; they
  // are then found again on the split level.
  WallCornerSearch search = FindWallCorners(*pass->mesh, corner_options);
  if (!search.corners.empty() && SplitStretchedEdgesNear(run, pass, AroundCorners(*pass->mesh, search))) {
    search = FindWallCorners(*pass->mesh, corner_options);
  }
  if (run.options.creases_start) run.options.creases_start(pass->level, *pass->mesh);
  // Vertical corners first (their bands end half an edge above the foot and below the
  // eave), then feet and eaves.
  std::stable_sort(search.corners.begin(), search.corners.end(),
                   [](const WallCorner& a, const WallCorner& b) { return a.kind < b.kind; });
  pass->report.corners_found = search.count(CreaseKind::kVertical);
  pass->report.feet_found = search.count(CreaseKind::kFoot);
  pass->report.eaves_found = search.count(CreaseKind::kEave);
  run.Say(FoundLine(run, *pass, search));
  SurfaceFaults faults = search.corners.empty() ? SurfaceFaults{} : CountSurfaceFaults(run, *pass->mesh);
  for (const WallCorner& corner : search.corners) TryCorner(run, pass, corner, corner_options, &faults);
  const LevelReport& r = pass->report;
  if (r.corners_laid + r.feet_laid + r.eaves_laid > 0 || r.corner_splits > 0) pass->UpdateProductsSurface();
}

}  // namespace facets
