#include "engine/pipeline/memory_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "engine/images/level_image_store.h"
#include "engine/pipeline/region_choice.h"
#include "engine/pipeline/start_stage.h"
#include "io/image_cache.h"
#include "mesh/tessellation.h"

namespace facets {
namespace {

constexpr double kMiB = 1024.0 * 1024.0;
// Calibrated on measured peaks (docs/BENCHMARKS.md, "Memory estimate"): a run of 135 TIN
// vertices peaks at 146 MB, one of 5000 at 309 MB, about 28 kB more per vertex.
constexpr double kProgramMb = 130.0;              // libraries, Embree device, TBB, allocator pools
constexpr double kEmbreeBytesPerFacet = 160.0;    // BVH, vertex and index buffers per triangle
constexpr double kBytesPerTinVertex = 23000.0;    // mesh, tessellation, grey values, searches, reports
constexpr double kWindowBytesPerFace = 40000.0;   // one window's observations and normal equations
// Open surfaces are larger than the region's largest face (walls, relief) and are refined
// where the images show detail: the block's finest TIN has 1.9 x the vertices of a
// plane over its region, the seed gable's 1.2 x.
constexpr double kSurfaceGrowth = 1.5;
constexpr int kFilterRows = 14;                 // rows the widest pyramid filter (meer13) spans

// Floats of the kept levels of one image (levels halve, rounding up).
double KeptLevelFloats(int width, int height, int channels, int levels, int finest_level) {
  double floats = 0.0;
  for (int l = 0; l < levels; ++l) {
    if (l >= finest_level) floats += static_cast<double>(width) * height * channels;
    width = (width + 1) / 2;
    height = (height + 1) / 2;
  }
  return floats;
}

// Bytes while one image is read: a strip of rows in the file's type and as floats, the
// filters' rows of every level and, for tiled files, a band of tiles per kept level.
double ReadingBytes(const ImageHeader& image, const MemoryJob& job) {
  const int channels = job.colour ? image.channels : 1;
  const double row = static_cast<double>(image.width);
  double bytes = kStripRows * row * image.channels * (image.bits / 8.0 + 4.0);
  bytes += 2.0 * kFilterRows * row * channels * 4.0;  // the rings of all levels: at most twice level 0's
  if (job.tiled) bytes += 2.0 * kTileSize * row * channels * 4.0;
  if (job.whole_images) bytes += row * image.height * image.channels * (image.bits / 8.0 + 8.0);
  return bytes;
}

std::string Gb(double mb) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f GB", mb / 1024.0);
  return text;
}

}  // namespace

std::string MemoryEstimate::Line(const MemoryLimit& available) const {
  return "memory estimate: " + Gb(TotalMb()) + " (images " + Gb(images_mb) + ", pyramid " + Gb(pyramid_mb) +
         ", Embree " + Gb(embree_mb) + ", normal equations " + Gb(equations_mb) + ", program " + Gb(program_mb) +
         "; " + std::to_string(tin_vertices) + " TIN vertices on the finest level); available " +
         (std::isfinite(available.mb) ? Gb(available.mb) : std::string("unknown")) + " (" + available.source + ")";
}

MemoryEstimate EstimateMemory(const MemoryJob& job) {
  MemoryEstimate estimate;
  estimate.program_mb = kProgramMb;
  // The images read at once are the largest ones in the worst case.
  std::vector<double> reading;
  double kept_floats = 0.0;
  for (const ImageHeader& image : job.images) {
    reading.push_back(ReadingBytes(image, job));
    kept_floats += KeptLevelFloats(image.width, image.height, job.colour ? image.channels : 1, job.levels,
                                   job.finest_level);
  }
  std::sort(reading.rbegin(), reading.rend());
  const size_t at_once = std::min<size_t>(reading.size(), static_cast<size_t>(std::max(1, job.threads)));
  for (size_t k = 0; k < at_once; ++k) estimate.images_mb += reading[k] / kMiB;
  estimate.pyramid_mb = job.tiled ? job.tile_cache_mb : kept_floats * 4.0 / kMiB;
  // A TIN of equilateral triangles with edge e: 2 / (sqrt(3) e^2) vertices per m^2.
  const double vertices = job.surface_m2 * 2.0 / (std::sqrt(3.0) * job.edge_m * job.edge_m);
  estimate.tin_vertices = static_cast<long long>(std::ceil(vertices));
  const double facets = 2.0 * vertices * kSubdivisions * kSubdivisions;
  estimate.embree_mb = facets * kEmbreeBytesPerFacet / kMiB;
  const double windows = std::max(1, job.threads) * std::min(2.0 * vertices, 1.0 * job.window_faces);
  estimate.equations_mb = (vertices * kBytesPerTinVertex + windows * kWindowBytesPerFace) / kMiB;
  return estimate;
}

double LevelImagesMb(const ImageBlock& block, const ReconstructionOptions& options) {
  double floats = 0.0;
  for (const auto& image : block.images) {
    const Camera& camera = block.CameraOf(image);
    floats += KeptLevelFloats(camera.width, camera.height, options.colour ? 3 : 1, options.levels,
                              options.finest_level);
  }
  return floats * 4.0 / kMiB;
}

double TileCacheMb(double image_memory_mb) { return std::max(64.0, 0.5 * image_memory_mb); }

MemoryJob DescribeMemoryJob(const ImageBlock& block, const ReconstructionOptions& options, int threads) {
  MemoryJob job;
  for (const auto& image : block.images) job.images.push_back(ReadImageHeader(image.path));
  job.levels = options.levels;
  job.finest_level = options.finest_level;
  job.colour = options.colour;
  job.threads = threads;
  job.tiled = options.image_cache_dir.has_value();
  job.tile_cache_mb = options.image_cache_mb;
  const bool closed = options.start_closed || !options.closed.mesh_file.empty();
  job.whole_images = options.adjustment.silhouette_weight > 0.0 || closed;
  const RegionOfInterest roi = ChooseRegion(block, options.roi);
  const Eigen::Vector3d size = (roi.max - roi.min).cwiseAbs();
  const double ground = size.x() * size.y(), front = size.x() * size.z(), side = size.y() * size.z();
  // Open surfaces: the largest face of the region (the ground, or a facade); closed
  // ones: an ellipsoid in the box, about half the box's surface.
  job.surface_m2 = closed ? 0.52 * 2.0 * (ground + front + side) : kSurfaceGrowth * std::max({ground, front, side});
  const double gsd0 = GroundPixel(block, 0.5 * (roi.min + roi.max));
  job.edge_m = kSubdivisions * options.facet_pixels * gsd0 * std::pow(2.0, options.finest_level);
  job.window_faces = options.windows.partition.max_faces;
  return job;
}

void CheckMemoryFits(const MemoryEstimate& estimate, const MemoryJob& job, const MemoryLimit& available) {
  if (!(estimate.TotalMb() > available.mb)) return;
  std::string change;
  const double others = estimate.TotalMb() - estimate.pyramid_mb;
  // A part is worth changing when it is a tenth of the total or half of what is available.
  auto large = [&](double mb) { return mb > 0.1 * estimate.TotalMb() || mb > 0.5 * available.mb; };
  if (!job.tiled && large(estimate.pyramid_mb)) {
    change += "; --image-memory " + std::to_string(static_cast<int>(std::max(64.0, 0.5 * (available.mb - others)))) +
              " (level images beyond it go to tiled files on disk)";
  } else if (job.tiled && large(job.tile_cache_mb)) {
    change += "; a smaller --image-memory (the tile cache is half of it)";
  }
  if (large(estimate.embree_mb + estimate.equations_mb)) {
    change += "; a smaller --roi, or --finest-level " + std::to_string(job.finest_level + 1) +
              " (a quarter of the TIN vertices: half the resolution)";
  }
  if (job.threads > 1) change += "; fewer --threads (images read and windows adjusted at once)";
  if (job.levels > job.finest_level + 1 && !job.tiled) change += "; fewer --levels";
  throw std::runtime_error(estimate.Line(available) + ": the job does not fit; change" +
                           (change.empty() ? std::string(" the machine") : change.substr(1)));
}

}  // namespace facets
