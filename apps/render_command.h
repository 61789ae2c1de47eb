// `facets render SCENE --out DIR [--seed N] [--noise SIGMA] [--supersampling S]`:
// renders a synthetic scene (scenes/data/*.json) into a data set with ground truth.
#pragma once

#include <CLI/CLI.hpp>

namespace facets {

void AddRenderCommand(CLI::App& app);

}  // namespace facets
