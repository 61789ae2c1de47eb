// `facets export RUN_DIR --out DIR [--formats ply,glb,wrl,ortho,dsm,sigma,preview]
//  [--raster-pixel M] [--crs CRS]`: re-exports a finished `facets reconstruct` run.
//
// What it reads from RUN_DIR: surface.ply (grey nodes and facets, object grey values,
// sigma, views; origin and CRS in its header) and, only for the default raster pixel,
// report.json (the finest level's ground pixel). It writes with the same code as
// `facets reconstruct` (engine/products.h, WriteSurfaceProducts).
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "engine/pipeline/products.h"

namespace facets {

struct ExportArgs {
  std::string run_dir;
  std::string out;
  std::string formats = kFormatNames;
  double raster_pixel = 0.0;  // 0: the run's finest ground pixel (report.json)
  std::string crs;            // overrides the run's CRS when given
};

// Reads the run folder (throws std::runtime_error naming the folder or file and what is
// missing or wrong), writes the products into args.out, returns the file names. The
// products go into a temporary copy of args.out that replaces it only when all are
// written (io/output_folder.h): a failure, SIGINT or SIGTERM leaves args.out, which may
// be the run folder itself, as it was.
std::vector<std::string> RunExport(const ExportArgs& args);

void AddExportCommand(CLI::App& app);

}  // namespace facets
