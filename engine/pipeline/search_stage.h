// Stage "search": before a level's adjustment, its steep vertices (walls and eaves a
// coarser level left several pixels off) search along their normals for the offset where
// the images agree best (engine/search/normal_search.h), then vertices try the planes of
// neighbours whose images agree (engine/search/plane_propagation.h); after the
// adjustment, rounds of search and trial (engine/pipeline/trial.h) while the level then
// fits better.
#pragma once

#include <vector>

#include "engine/pipeline/run_context.h"
#include "engine/search/normal_search.h"
#include "engine/search/plane_propagation.h"

namespace facets {

// The searches of one level; they read its whole images once, freed with the level.
class LevelSearch {
 public:
  LevelSearch(const RunContext& run, LevelPass* pass) : run_(run), pass_(pass) {}
  // Whether this level is searched at all: on (or auto for plane and tie-point starts),
  // below the coarsest, not below normal_search_last_level.
  bool Active() const;
  // Normal search, then plane propagation; the propagation's moves are added to the
  // report's `moved` (the rounds go on while either moved something).
  NormalSearchReport Search(PlanePropagationReport* planes);

 private:
  const RunContext& run_;
  LevelPass* pass_;
  ImageStorage storage_;
  std::vector<LevelImage> images_;
};

// Whether the run searches along normals (auto: for plane and tie-point starts).
bool NormalSearchOn(const RunContext& run);

// Before the level's adjustment.
void SearchBeforeLevel(const RunContext& run, LevelPass* pass, LevelSearch* search);

// After the level's adjustment: rounds of search and trial, kept while they fit better.
void SearchRounds(const RunContext& run, LevelPass* pass, LevelSearch* search);

}  // namespace facets
