#include "apps/reconstruct_command.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/reconstruct_options.h"
#include "engine/pipeline/geometry_check.h"
#include "engine/pipeline/products.h"
#include "engine/pipeline/reconstruction.h"
#include "engine/pipeline/radiometry_choice.h"
#include "engine/pipeline/scene_preset.h"
#include "io/atomic_file.h"
#include "io/colmap_io.h"
#include "io/ply_io.h"
#include "io/project_io.h"
#include "mesh/closed_surface.h"

namespace facets {
namespace {

using Say = std::function<void(const std::string&)>;

ImageBlock ReadBlock(const ReconstructAppSettings& app, const Say& say) {
  ImageBlock block;
  if (!app.project.empty()) {
    say("reading project " + app.project);
    block = ReadProject(app.project);
  } else {
    if (app.colmap.empty() || app.images.empty()) {
      throw std::invalid_argument("give --project FILE, or --colmap SPARSE_DIR and --images IMAGE_DIR");
    }
    say("reading COLMAP model " + app.colmap + " with images in " + app.images);
    block = ReadColmapModel(app.colmap, app.images);
  }
  if (!app.principal_point_shift.empty()) {
    const double dx = app.principal_point_shift[0], dy = app.principal_point_shift[1];
    ShiftPrincipalPoints(block, dx, dy);
    std::ostringstream shift;
    shift << "principal points shifted by (" << dx << ", " << dy << ") pixels";
    say(shift.str());
  }
  say(std::to_string(block.images.size()) + " images, " + std::to_string(block.cameras.size()) + " cameras, " +
      std::to_string(block.points.size()) + " tie points");
  return block;
}

// --roi in the block's local coordinates; nullopt when not given.
std::optional<RegionOfInterest> GivenRegion(const ReconstructAppSettings& app, const ImageBlock& block) {
  if (app.roi.empty()) return std::nullopt;
  if (app.roi.size() != 6) throw std::invalid_argument("--roi takes 6 numbers: xmin ymin zmin xmax ymax zmax");
  RegionOfInterest roi;
  roi.min = Eigen::Vector3d(app.roi[0], app.roi[1], app.roi[2]) - block.origin;
  roi.max = Eigen::Vector3d(app.roi[3], app.roi[4], app.roi[5]) - block.origin;
  return roi;
}

// The scene preset (given, or chosen from the cameras and tie points) over the library's
// defaults, then the options given over the preset; line->app.scene becomes the preset used.
void ChooseOptions(const ImageBlock& block, ReconstructCommandLine* line, const Say& say) {
  ScenePreset preset = line->app.scene;
  if (preset == ScenePreset::kAuto) {
    std::string why;
    preset = ChooseScenePreset(block, &why);
    say("scene: " + ScenePresetName(preset) + " (chosen: " + why + ")");
  } else {
    say("scene: " + ScenePresetName(preset) + " (given)");
  }
  line->app.scene = preset;
  std::function<void(ReconstructionOptions*)> from_data;
  if (!OptionGiven(*line, "--radiometry")) {
    const RadiometryChoice radiometry = ChooseRadiometry(block);
    say("radiometry: " + radiometry.why);
    from_data = [model = radiometry.model](ReconstructionOptions* options) { options->adjustment.radiometry = model; };
  }
  const SceneApplication applied = ApplySceneAndGivenOptions(preset, line, from_data);
  say("  the preset and the images set: " + (applied.preset.empty() ? std::string("nothing") : applied.preset));
  say("  options given: " + (applied.given.empty() ? std::string("none") : applied.given));
}

// Level images in memory while they fit the budget, else tiled on disk and read per
// window (pyramid: 4/3 of the finest kept level; float per channel).
void PlaceLevelImages(const ImageBlock& block, const ReconstructAppSettings& app, ReconstructionOptions* options,
                      const Say& say) {
  double pyramid_mb = 0.0;
  for (const auto& image : block.images) {
    const Camera& camera = block.CameraOf(image);
    pyramid_mb += 4.0 / 3.0 * std::pow(0.25, options->finest_level) * camera.width * camera.height *
                  (options->colour ? 3 : 1) * 4.0 / (1024.0 * 1024.0);
  }
  if (app.tiled_images || pyramid_mb > app.image_memory_mb) {
    options->image_cache_dir = (std::filesystem::path(app.out) / ".image-cache").string();
    options->image_cache_mb = std::max(64.0, 0.5 * app.image_memory_mb);
    say("level images: " + std::to_string(static_cast<int>(pyramid_mb)) + " MB, read per window from tiled files");
  }
}

// The TIN of each level into OUT/levels/level_K.ply, and the one the wall crease step
// starts from (to replay that step without images: `facets creases`).
void KeepLevels(const std::string& out, ReconstructionOptions* options) {
  const std::filesystem::path dir = std::filesystem::path(out) / "levels";
  std::filesystem::create_directories(dir);
  auto keep = [dir](const std::string& name, const TinMesh& mesh) {
    const std::string path = (dir / name).string();
    WritePly(path + ".tmp", TinGeometryData(mesh));
    CommitTemporary(path + ".tmp", path);
  };
  options->level_done = [keep](int level, const TinMesh& mesh) {
    keep("level_" + std::to_string(level) + ".ply", mesh);
  };
  options->creases_start = [keep](int level, const TinMesh& mesh) {
    keep("level_" + std::to_string(level) + "_creases.ply", mesh);
  };
}

// The run's options beyond the bound ones: region, image placement, progress, outputs.
void PrepareRun(const ImageBlock& block, ReconstructCommandLine* line, const Say& say) {
  const ReconstructAppSettings& app = line->app;
  ReconstructionOptions& options = line->options;
  options.closed.write_start = (std::filesystem::path(app.out) / "start.ply").string();
  PlaceLevelImages(block, app, &options, say);
  options.roi = GivenRegion(app, block);
  options.progress = say;
  if (app.keep_levels) KeepLevels(app.out, &options);
}

// Products (each written to a temporary name and renamed: io/atomic_file.h) and the
// closing lines of the log.
void WriteRunProducts(const Reconstruction& result, const ImageBlock& block, const ReconstructCommandLine& line,
                      std::chrono::steady_clock::time_point start, const Say& say) {
  const ReconstructAppSettings& app = line.app;
  say("stage products: writing into " + app.out);
  ProductOptions products;
  products.glb = app.glb;
  products.vrml = app.vrml;
  products.ortho = products.dsm = products.sigma = app.rasters;
  products.preview = app.preview;
  std::string list;
  for (const auto& file : WriteProducts(result, block, app.out, products)) list += " " + file;
  say("  written:" + list);
  if (line.options.start_closed || !line.options.closed.mesh_file.empty()) {
    // A closed start must come out closed and without self-intersections.
    say("closed surface: TIN " + CheckClosedSurface(result.mesh).Brief() + "; surface facets " +
        CheckClosedSurface(result.tessellation.points, result.tessellation.triangles).Brief());
  }
  const WindowReport& finest = result.report.levels.back().window;
  if (finest.background > 0 || finest.rejected > 0 || finest.downweighted > 0) {
    const double all = static_cast<double>(std::max<long long>(finest.observations + finest.rejected, 1));
    say("finest level: " + std::to_string(finest.background) + " background pixels dropped, " +
        std::to_string(finest.rejected) + " observations rejected (" + std::to_string(100.0 * finest.rejected / all) +
        " %), " + std::to_string(finest.downweighted) + " down-weighted (" +
        std::to_string(100.0 * finest.downweighted / all) + " %)");
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  int flagged = 0;
  for (uint8_t f : result.vertex_flags) flagged += f != 0 ? 1 : 0;
  say("summary: " + std::to_string(result.mesh.n_vertices()) + " vertices (" + std::to_string(flagged) +
      " flagged), " + std::to_string(result.tessellation.triangles.size()) + " surface facets, sigma0 " +
      std::to_string(finest.sigma0) + " grey values, " + std::to_string(seconds) + " s; products in " + app.out);
}

void RunReconstruct(const CLI::App& sub, ReconstructCommandLine* line) {
  const auto start = std::chrono::steady_clock::now();
  const ReconstructAppSettings& app = line->app;
  std::filesystem::create_directories(app.out);
  std::ostringstream log;
  const Say say = [&log](const std::string& text) {
    std::cout << text << "\n" << std::flush;
    log << text << "\n";
  };
  std::unique_ptr<tbb::global_control> threads;
  if (app.threads > 0) {
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, app.threads);
  }
  ImageBlock block = ReadBlock(app, say);
  GeometryCheck geometry;
  block = CheckedBlock(block, GivenRegion(app, block), say, &geometry);
  ChooseOptions(block, line, say);
  const std::string settings = SettingsFile(sub);
  PrepareRun(block, line, say);
  Reconstruction result = Reconstruct(block, line->options);
  result.report.geometry = std::move(geometry);
  WriteRunProducts(result, block, *line, start, say);
  const std::filesystem::path out(app.out);
  WriteFileAtomically((out / "settings.ini").string(), settings);
  WriteFileAtomically((out / "facets.log").string(), log.str());
}

}  // namespace

void AddReconstructCommand(CLI::App& app) {
  auto line = std::make_shared<ReconstructCommandLine>();
  CLI::App* sub = app.add_subcommand("reconstruct", "reconstruct the surface from oriented images");
  // `facets reconstruct --config FILE`: the option belongs to the top-level app (see
  // apps/facets_main.cc) and falls through to it.
  sub->fallthrough();
  BindReconstructOptions(sub, line.get());
  sub->callback([line, sub] {
    try {
      RunReconstruct(*sub, line.get());
    } catch (const std::exception& e) {
      std::cerr << "facets reconstruct: error: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace facets
