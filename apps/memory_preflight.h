// `facets reconstruct`'s memory check before any pixel is read: the run's estimated
// peak (engine/pipeline/memory_estimate.h) said, and the run stopped with the estimate
// and what to change when it exceeds the memory the process may use.
#pragma once

#include <functional>
#include <string>

#include "apps/reconstruct_options.h"
#include "io/image_block.h"

namespace facets {

// Reads the images' headers only. Throws std::runtime_error when the job cannot fit.
void CheckRunMemory(const ImageBlock& block, const ReconstructCommandLine& line,
                    const std::function<void(const std::string&)>& say);

// The message for a std::bad_alloc that escaped the run during `stage` (its last
// "stage ..." or "reading ..." progress line).
std::string OutOfMemoryMessage(const std::string& stage);

}  // namespace facets
