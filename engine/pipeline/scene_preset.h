// Scene presets: what a kind of scene needs set, named in one word. The user names one
// (`--scene aerial|facade|object`) or the cameras and tie points choose it (auto).
//   aerial  nadir and oblique images over a built-up area: walls stand up and are
//           refined (search along normals in local rounds, a V-cycle, 1.5-pixel grey
//           facets, vertical corners, feet and eaves laid onto their walls), 4 levels.
//   facade  images from the street at one side of a facade: a start plane fitted to the
//           tie points, no wall searches (the steep parts there are street and sky).
//   object  images all around a close-range object: a closed start carved from the
//           silhouettes, robust weights, the silhouette term, the surface held inside
//           the visual hull.
// The radiometric model per image is not a preset's: the images decide it
// (engine/pipeline/radiometry_choice.h). Options the user gives explicitly are set after
// the preset and win.
#pragma once

#include <string>

#include "engine/pipeline/reconstruction.h"
#include "io/image_block.h"

namespace facets {

enum class ScenePreset { kAuto, kAerial, kFacade, kObject };

// "auto", "aerial", "facade", "object"; throws std::invalid_argument on anything else.
ScenePreset ParseScenePreset(const std::string& name);
std::string ScenePresetName(ScenePreset preset);

// The preset the cameras and tie points point to, with the reason in one line (*why).
// Aerial: the images' mean viewing direction is longer than 0.7 (they look one way) and
// within 45 deg of -Z, and the tie points spread less than half as far along Z as across
// it. Object: the viewing directions cancel out to a mean shorter than 0.5 (the images
// look from all sides), or the cameras surround the tie points' centre (no gap of 150 deg
// or more in their azimuths about up: the cameras' mean up where they agree on one,
// else Z). Facade: the rest (the cameras on one side).
ScenePreset ChooseScenePreset(const ImageBlock& block, std::string* why);

// Sets on *options what the preset means (kAuto: nothing).
void ApplyScenePreset(ScenePreset preset, ReconstructionOptions* options);

}  // namespace facets
