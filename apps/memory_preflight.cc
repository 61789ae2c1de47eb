#include "apps/memory_preflight.h"

#include <tbb/info.h>

#include "engine/pipeline/memory_estimate.h"
#include "io/system_memory.h"

namespace facets {

void CheckRunMemory(const ImageBlock& block, const ReconstructCommandLine& line,
                    const std::function<void(const std::string&)>& say) {
  const ReconstructAppSettings& app = line.app;
  const int threads = app.threads > 0 ? app.threads : tbb::info::default_concurrency();
  ReconstructionOptions options = line.options;
  if (app.roi.size() == 6) {  // as PrepareRun will set it (checked there)
    options.roi = RegionOfInterest{Eigen::Vector3d(app.roi[0], app.roi[1], app.roi[2]) - block.origin,
                                   Eigen::Vector3d(app.roi[3], app.roi[4], app.roi[5]) - block.origin};
  }
  MemoryJob job = DescribeMemoryJob(block, options, threads);
  // As the command places the level images (reconstruct_command.cc, PlaceLevelImages).
  job.tiled = app.tiled_images || LevelImagesMb(block, options) > app.image_memory_mb;
  job.tile_cache_mb = TileCacheMb(app.image_memory_mb);
  const MemoryEstimate estimate = EstimateMemory(job);
  const MemoryLimit available = AvailableMemory();
  say(estimate.Line(available));
  CheckMemoryFits(estimate, job, available);
}

std::string OutOfMemoryMessage(const std::string& stage) {
  return "out of memory (std::bad_alloc) during \"" + stage +
         "\"; the memory estimate at the start of the log says which part is large: lower --image-memory, give a "
         "smaller --roi, a coarser --finest-level or fewer --threads";
}

}  // namespace facets
