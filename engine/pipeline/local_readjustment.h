// A local re-adjustment of a level (the trials of engine/pipeline/trial.h): after a stage
// moved some vertices of an adjusted level, only the windows over the faces within a few
// edge rings of them run again (LocalScope, engine/pipeline/level_windows.h). A judged
// trial is judged by those windows' sigma0 before and after it, each from one
// linearisation of a copy (the probes): a few windows instead of the whole level.
#pragma once

#include <functional>
#include <string>

#include "engine/pipeline/level_windows.h"
#include "mesh/tin.h"

namespace facets {

struct LocalReadjustment {
  // The level's adjustment with the local windows' results in: surface, per-vertex and
  // grey values, each face's part of the fit (FaceFit); its summary's sigma0,
  // observations and redundancy those of the whole level from the faces' parts; per-window
  // reports those of `adjusted`.
  LevelAdjustment level;
  // Of the local windows. Probed: each from one linearisation of a copy with the same
  // windows, on `before` and on the surface their adjustment left (two measures of the same
  // kind). Not probed: the faces' parts of the level's fit over their cores, before (from
  // the windows that adjusted those faces last) and after (from the local windows' runs).
  double sigma0_before = 0.0;
  double sigma0_after = 0.0;
  bool probed = false;
  int windows = 0;             // 0: no vertex moved, nothing done
};

// `mesh` is `before` with some vertices moved (same vertex and face counts; edges among
// the faces around moved vertices may be flipped, as the crease straightening does:
// those faces are in the local windows' cores, so no grey value of `adjusted` is taken
// for them by face index); `adjusted` is the adjustment `before` came from. Windows over
// the faces within `rings` edge rings of the moved vertices are adjusted in place, one
// sweep over them whatever `options.sweeps` says; `probed`: with the two probes (a
// judged trial).
LocalReadjustment ReadjustAroundMovedVertices(TinMesh* mesh, const TinMesh& before,
                                              const LevelAdjustment& adjusted, int rings,
                                              const WindowImages& images,
                                              const AdjustmentOptions& adjustment,
                                              const LevelWindowOptions& options, bool keep_grey, bool probed,
                                              const std::function<void(const std::string&)>& progress);

// The same after edges were split (and flipped) since `adjusted`: `mesh` is `before`
// with vertices and faces appended and some faces' corners changed (VerticesChangedFrom,
// mesh/local_ops.h). The windows over the faces within `rings` rings of the changed
// vertices are adjusted (those of `mesh`), without probes (the splits are not judged); the
// level's per-vertex values and fit of the inserted vertices and faces come from their windows.
LocalReadjustment ReadjustAroundSplits(TinMesh* mesh, const TinMesh& before, const LevelAdjustment& adjusted,
                                       int rings, const WindowImages& images, const AdjustmentOptions& adjustment,
                                       const LevelWindowOptions& options, bool keep_grey,
                                       const std::function<void(const std::string&)>& progress);

}  // namespace facets
