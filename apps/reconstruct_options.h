// The options of `facets reconstruct`, each bound once: straight to its field of
// ReconstructionOptions (engine/pipeline/reconstruction.h) or of the command's own
// settings (ReconstructAppSettings). `--help` lists the options a user needs in the
// groups Input, Region, Quality, Products and Performance; the expert options sit in the
// group Expert, listed by `--help-all` only, and every option can be set in a --config
// file.
//
// Scene presets (engine/pipeline/scene_preset.h): the options start from the library's
// defaults with the preset applied over them; the options given on the command line or
// in the --config file are then set over the preset (ApplySceneAndGivenOptions).
#pragma once

#include <functional>

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "engine/pipeline/reconstruction.h"
#include "engine/pipeline/scene_preset.h"

namespace facets {

// Settings of the command, not of the reconstruction: inputs, outputs, resources.
struct ReconstructAppSettings {
  std::string colmap;   // COLMAP text model folder
  std::string images;   // the model's image folder
  std::string project;  // native project file (JSON)
  std::string out;      // output folder
  std::vector<double> roi;                    // xmin ymin zmin xmax ymax zmax, global (m); empty: none
  std::vector<double> principal_point_shift;  // dx dy in pixels; empty: none
  std::string exclude_images;  // images left out (io/image_subset.h syntax); empty: none
  ScenePreset scene = ScenePreset::kAuto;
  int threads = 0;                // 0: all cores
  double image_memory_mb = 1024.0;  // level images in memory up to this, the rest tiled on disk
  bool tiled_images = false;        // level images tiled on disk whatever their size
  bool glb = true, vrml = true, rasters = true, preview = true;  // products written
  bool keep_levels = false;  // each level's TIN into OUT/levels
};

// Everything the command line binds to. Lives at a fixed address (the bindings refer to
// its fields) for the whole parse and run.
struct ReconstructCommandLine {
  ReconstructionOptions options;
  ReconstructAppSettings app;
  std::vector<CLI::Option*> engine_options;  // the options bound to `options`, in binding order
};

// Adds every option of the command to *sub, bound to *line, and the help formatter that
// hides the group Expert unless --help-all is given.
void BindReconstructOptions(CLI::App* sub, ReconstructCommandLine* line);

// What ApplySceneAndGivenOptions set, as `key=value` lists (option names without --).
struct SceneApplication {
  std::string preset;  // the preset's values that differ from the library's defaults
  std::string given;   // the options given on the command line or in the --config file
};

// line->options = the library's defaults, the preset applied over them, then every option
// given on the command line or in the --config file set again over that.
// `from_data` (may be empty) sets what the images decide (radiometry) after the preset.
SceneApplication ApplySceneAndGivenOptions(ScenePreset preset, ReconstructCommandLine* line,
                                           const std::function<void(ReconstructionOptions*)>& from_data = {});
// Whether the option (e.g. "--radiometry") was given on the command line or in --config.
bool OptionGiven(const ReconstructCommandLine& line, const std::string& name);

// Every option of `sub` with its current value in the form --config reads: a
// [reconstruct] section of `key=value` lines (options without a value left out).
std::string SettingsFile(const CLI::App& sub);

}  // namespace facets
