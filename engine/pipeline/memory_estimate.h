// The peak memory of a reconstruction, estimated before any pixel is read (from the
// images' headers, the region and the options) and checked against the memory the
// process may use (io/system_memory.h), so that a job that cannot fit stops at once
// with the figures and what to change instead of dying in std::bad_alloc hours later.
// Calibrated against measured peaks (docs/BENCHMARKS.md, "Memory estimate").
#pragma once

#include <string>
#include <vector>

#include "engine/pipeline/reconstruction.h"
#include "io/image_block.h"
#include "io/image_io.h"
#include "io/system_memory.h"

namespace facets {

// What the estimate depends on.
struct MemoryJob {
  std::vector<ImageHeader> images;  // from the files' headers
  int levels = 3;
  int finest_level = 0;  // levels below are built while reading but not kept
  bool colour = false;
  int threads = 1;       // images read and windows adjusted at once
  bool tiled = false;    // level images in tiled files (then tile_cache_mb of tiles)
  double tile_cache_mb = 0.0;
  bool whole_images = false;  // silhouettes or a visual hull decode whole images
  double surface_m2 = 0.0;    // area of the surface to reconstruct
  double edge_m = 1.0;        // TIN edge on the finest adjusted level
  int window_faces = 400;     // faces of one window (LevelWindowOptions)
};

// MiB per part of the peak.
struct MemoryEstimate {
  double program_mb = 0.0;    // the program and its libraries
  double images_mb = 0.0;     // reading: strips and the pyramid filters' rows per image read at once
  double pyramid_mb = 0.0;    // level images kept in memory, or the tile cache
  double embree_mb = 0.0;     // Embree scenes of the tessellated surface
  double equations_mb = 0.0;  // the TIN, its tessellation and the windows' normal equations
  long long tin_vertices = 0;  // finest level, estimated
  double TotalMb() const { return program_mb + images_mb + pyramid_mb + embree_mb + equations_mb; }
  // "memory estimate: X GB (images A, pyramid B, Embree C, normal equations D); available Y GB (source)"
  std::string Line(const MemoryLimit& available) const;
};

MemoryEstimate EstimateMemory(const MemoryJob& job);

// MiB of the level images kept (levels finest_level..levels-1 of every camera, grey or
// three channels, float): above --image-memory they go to tiled files.
double LevelImagesMb(const ImageBlock& block, const ReconstructionOptions& options);

// MiB of tiles the cache of tiled level images keeps, for an --image-memory budget.
double TileCacheMb(double image_memory_mb);

// The job of a reconstruction: image sizes from the headers (no pixels decoded), the
// region, ground pixel and TIN edge as the start stage will choose them.
MemoryJob DescribeMemoryJob(const ImageBlock& block, const ReconstructionOptions& options, int threads);

// Throws std::runtime_error when the estimate exceeds `available`: the message gives
// the estimate, the limit and what to change (--image-memory, --roi, --finest-level,
// --levels, --threads) for the parts that dominate.
void CheckMemoryFits(const MemoryEstimate& estimate, const MemoryJob& job, const MemoryLimit& available);

}  // namespace facets
