// A local re-adjustment of a level (the trials of engine/pipeline/trial.h): after a stage
// moved some vertices of an adjusted level, only the windows over the faces within a few
// edge rings of them run again (LocalScope, engine/pipeline/level_windows.h), and the
// trial is judged by those windows' sigma0 before and after it (one linearisation each):
// a few windows instead of the whole level.
#pragma once

#include <functional>
#include <string>

#include "engine/pipeline/level_windows.h"
#include "mesh/tin.h"

namespace facets {

struct LocalReadjustment {
  // The level's adjustment with the local windows' results in: surface, per-vertex and
  // grey values; its summary's sigma0, observations and redundancy pooled with the local
  // windows' share replaced (margins counted in every window that holds them, as in the
  // level's own pooling; their converged sigma0 before estimated from the one after and
  // the two probes); per-window reports those of `adjusted`.
  LevelAdjustment level;
  // Of the local windows, each from one linearisation of a copy: on `before`, and on the
  // surface their adjustment left.
  double sigma0_before = 0.0;
  double sigma0_after = 0.0;
  int windows = 0;             // 0: no vertex moved, nothing done
};

// `mesh` is `before` with some vertices moved (same vertex and face counts; edges among
// the faces around moved vertices may be flipped, as the crease straightening does:
// those faces are in the local windows' cores, so no grey value of `adjusted` is taken
// for them by face index); `adjusted` is the adjustment `before` came from. Windows over
// the faces within `rings` edge rings of the moved vertices are adjusted in place, one
// sweep over them whatever `options.sweeps` says.
LocalReadjustment ReadjustAroundMovedVertices(TinMesh* mesh, const TinMesh& before,
                                              const LevelAdjustment& adjusted, int rings,
                                              const WindowImages& images,
                                              const AdjustmentOptions& adjustment,
                                              const LevelWindowOptions& options, bool keep_grey,
                                              const std::function<void(const std::string&)>& progress);

// The same after edges were split (and flipped) since `adjusted`: `mesh` is `before`
// with vertices and faces appended and some faces' corners changed (VerticesChangedFrom,
// mesh/local_ops.h). The windows over the faces within `rings` rings of the changed
// vertices are adjusted (those of `mesh`) and probed before (those of `before`); the
// level's per-vertex values of the inserted vertices come from their windows.
LocalReadjustment ReadjustAroundSplits(TinMesh* mesh, const TinMesh& before, const LevelAdjustment& adjusted,
                                       int rings, const WindowImages& images, const AdjustmentOptions& adjustment,
                                       const LevelWindowOptions& options, bool keep_grey,
                                       const std::function<void(const std::string&)>& progress);

}  // namespace facets
