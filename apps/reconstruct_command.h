// `facets reconstruct --colmap SPARSE_DIR --images IMAGE_DIR --out OUT_DIR [options]`
// `facets reconstruct --project FILE --out OUT_DIR [options]`
// Reads the block, takes the scene preset (--scene, or chosen from the cameras and tie
// points: engine/pipeline/scene_preset.h) and sets the options given over it
// (apps/reconstruct_options.h), reconstructs the surface and writes into OUT_DIR
// (engine/pipeline/products.h): surface.ply, surface.glb, surface.wrl (tessellated
// surface with the object grey values, per-node sigma and views), tin.ply, ortho.tif,
// dsm.tif, sigma.tif, report.json, facets.log, and settings.ini: every option of the run
// as used, which `--config settings.ini` reads back (a [reconstruct] section of
// `key=value` lines; options on the command line win).
// Exit status 0 only when the products were written.
#pragma once

#include <CLI/CLI.hpp>

namespace facets {

void AddReconstructCommand(CLI::App& app);

}  // namespace facets
