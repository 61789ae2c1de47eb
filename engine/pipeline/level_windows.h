// One pyramid level adjusted in windows (DESIGN.md section 2): the level's TIN is split
// into overlapping windows of a few hundred geometry triangles (mesh/windows.h), each
// adjusted on its own with its margin's outer vertices held fixed, only its core
// vertices kept. Windows that share no vertex run in parallel (TBB); groups of such
// windows run one after another, so a window sees the results of the groups before it
// (a multiplicative Schwarz sweep). The rest of the surface is in each window's Embree
// scene as occluder: a pixel that sees a neighbouring building first is no
// observation of the window behind it.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "engine/solver/adjustment_options.h"
#include "engine/images/level_image_store.h"
#include "engine/solver/window_adjustment.h"
#include "mesh/tessellation.h"
#include "mesh/tin.h"
#include "mesh/windows.h"

namespace facets {

struct LevelWindowOptions {
  WindowPartitionOptions partition;
  // Sweeps over all windows (2+: windows processed early see their neighbours'
  // results too; seams shrink).
  int sweeps = 2;
  // Sweeps (from the first) in which the margin's outer vertices are estimated too
  // instead of held fixed: on the first sweep the neighbours still sit at the start
  // values (possibly decimetres off), and holding them would bend the margin and pull
  // the core; later sweeps hold them at their adjusted values.
  int free_margin_sweeps = 1;
  // Put the surface outside the window into its scene as occluder.
  bool occluders = true;
  // One more window run with the crease set found after the first, when the
  // adjustment sharpened new creases (a ridge grown out of a plane start).
  bool crease_second_pass = true;
  void Check() const;
};

// Each face's part of a level's fit: the window whose core holds the face (its last run)
// gives each of its core faces an equal part of its sigma0^2 r, redundancy and
// observations; a face in no observed core has none. The parts of all faces sum to the
// level's pooled figures. A local run (LocalScope) replaces the parts of its cores' faces
// and keeps the others', so the level's fit stays defined over the whole level without
// running its other windows again.
struct FaceFit {
  std::vector<double> vpv, redundancy, observations;
  // sqrt(sum vpv / sum redundancy) over `faces` (every face when null); 0 without redundancy.
  double Sigma0(const std::vector<int>* faces = nullptr) const;
  double TotalRedundancy() const;
  double TotalObservations() const;
};

struct LevelAdjustment {
  // Summary of the level: converged = every window converged; sigma0 pooled over the
  // windows (sqrt of sum sigma0^2 r / sum r, margins counted in every window that
  // holds them); counts summed; iterations = those of the window that needed most;
  // per-vertex values from each vertex's own window.
  WindowReport summary;
  std::vector<WindowReport> windows;  // in window order (last sweep)
  std::vector<int> window_core_faces;
  int groups = 0;
  FaceFit face_fit;
  // Of the whole level when requested (keep_grey): the tessellation of the final
  // surface (creases as DetectCreaseEdges finds them) and the object grey values per
  // node, each face's from the window whose core holds it.
  Tessellation tessellation;
  std::vector<double> grey;
};

// The images a window gets: those whose view overlaps the box, with pixels at least
// over its projection; regions read for the window go into the storage, which lives
// as long as the window's adjustment (engine/images/level_image_store.h).
using WindowImages = std::function<std::vector<LevelImage>(const Eigen::AlignedBox3d& box,
                                                           ImageStorage* storage)>;

// A local re-adjustment: after a search moved some vertices of an adjusted level, only
// windows around them run again (PartitionFacesIntoWindows, mesh/windows.h); their
// margins are held at the level's values from the first sweep on. The summary's counts
// and sigma0 are then those of these windows only; per-vertex values and grey values
// (keep_grey) of the rest of the level come from `previous` (the level's adjustment
// before, same topology).
struct LocalScope {
  std::vector<MeshWindow> windows;
  const LevelAdjustment* previous = nullptr;
};

LevelAdjustment AdjustLevelInWindows(TinMesh* mesh, const WindowImages& images,
                                     const AdjustmentOptions& adjustment,
                                     const LevelWindowOptions& options, bool keep_grey,
                                     const std::function<void(const std::string&)>& progress,
                                     const LocalScope* local = nullptr);

// Same with whole images in memory.
// Adjusts *mesh (vertex normals set) in place. progress gets one line per window.
// Throws std::runtime_error when no window has any observation.
LevelAdjustment AdjustLevelInWindows(TinMesh* mesh, const std::vector<LevelImage>& images,
                                     const AdjustmentOptions& adjustment,
                                     const LevelWindowOptions& options, bool keep_grey,
                                     const std::function<void(const std::string&)>& progress,
                                     const LocalScope* local = nullptr);

}  // namespace facets
