// The expert options of `facets reconstruct` (help group Expert, `--help-all`): every
// further field of ReconstructionOptions a run may want to set, bound straight to it.
#pragma once

#include "apps/option_binder.h"
#include "engine/pipeline/reconstruction.h"

namespace facets {

void BindExpertOptions(const OptionBinder& bind, ReconstructionOptions& options);

}  // namespace facets
