// `facets evaluate --truth DIR --mesh FILE [--json OUT.json]`: scores a reconstructed
// mesh (PLY or OBJ) against the truth folder written by `facets render`; prints the
// accuracy / completeness table and optionally writes the report as JSON.
// See docs/EVALUATION.md for what the numbers mean.
#pragma once

#include <CLI/CLI.hpp>

namespace facets {

void AddEvaluateCommand(CLI::App& app);

}  // namespace facets
