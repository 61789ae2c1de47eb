// Test helper: a bundled or test scene rendered into a folder and read back as the
// block a user would give `facets reconstruct` (COLMAP model + images), with the
// scene's window as region of interest.
//
// Each scene is rendered once per process: a later request for the same scene file with
// the same render options returns the first render (in the first request's folder). ctest
// runs every test case in its own process, so this spares the renders a test repeats and,
// when a test binary runs whole, the renders its tests share.
#pragma once

#include <map>
#include <set>
#include <string>

#include "io/colmap_io.h"
#include "io/image_block.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"

namespace facets {

struct RenderedScene {
  Scene scene;
  std::string dir;
  ImageBlock block;
};

// The render options that change the images or the tie points, as text.
inline std::string RenderOptionsKey(const RenderOptions& options) {
  std::string key;
  if (options.seed) key += " seed=" + std::to_string(*options.seed);
  if (options.noise_sigma) key += " noise=" + std::to_string(*options.noise_sigma);
  if (options.supersampling) key += " supersampling=" + std::to_string(*options.supersampling);
  return key;
}

// Renders `scene`, loaded unchanged from `scene_file` (its full path), into `dir` unless this process
// rendered that file with the same options before. Returns the folder holding the render:
// `dir`, the folder of the earlier render, or `dir`_N when `dir` holds another render.
inline std::string RenderSceneOnce(const std::string& scene_file, const Scene& scene,
                                   const std::string& dir, const RenderOptions& options = {}) {
  static std::map<std::string, std::string> folders;  // scene file + options -> folder
  static std::set<std::string> used;                   // folders holding a render
  const std::string key = scene_file + RenderOptionsKey(options);
  if (auto it = folders.find(key); it != folders.end()) return it->second;
  // Rendering replaces the folder: one that holds another render of this process (an
  // earlier request for other options) is kept, and `dir`_2, `dir`_3, ... is used.
  std::string folder = dir;
  for (int n = 2; used.count(folder); ++n) folder = dir + "_" + std::to_string(n);
  RenderScene(scene, folder, options);
  used.insert(folder);
  folders.emplace(key, folder);
  return folder;
}

// scene_file relative to the source tree, e.g. "scenes/data/seed_gable_parallel.json".
// Rendered once per process (see above); `dir` is where the first request renders.
inline RenderedScene RenderAndRead(const std::string& scene_file, const std::string& dir) {
  static std::map<std::string, RenderedScene> rendered;  // scene file -> scene and block
  if (auto it = rendered.find(scene_file); it != rendered.end()) return it->second;
  const std::string path = std::string(FACETS_SOURCE_DIR) + "/" + scene_file;
  RenderedScene r;
  r.scene = LoadScene(path);
  r.dir = RenderSceneOnce(path, r.scene, dir);
  r.block = ReadColmapModel(r.dir + "/sparse", r.dir + "/images");
  r.block.roi = r.scene.roi;
  return rendered.emplace(scene_file, r).first->second;
}

}  // namespace facets
