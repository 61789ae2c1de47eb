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
#include <mutex>
#include <new>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/option_binder.h"
#include "apps/memory_preflight.h"
#include "apps/reconstruct_options.h"
#include "engine/pipeline/background_choice.h"
#include "engine/pipeline/memory_estimate.h"
#include "engine/pipeline/geometry_check.h"
#include "engine/pipeline/products.h"
#include "engine/pipeline/reconstruction.h"
#include "engine/pipeline/radiometry_choice.h"
#include "engine/pipeline/scene_preset.h"
#include "apps/stop_on_signal.h"
#include "io/atomic_file.h"
#include "io/colmap_io.h"
#include "io/output_folder.h"
#include "io/image_subset.h"
#include "io/ply_io.h"
#include "io/project_io.h"
#include "mesh/closed_surface.h"
#include "visibility/embree_scene.h"

namespace facets {
namespace {

using Say = std::function<void(const std::string&)>;

// The run's log (facets.log, or <out>.failed.log): lines said by the run, read by a
// signal watcher thread too.
class RunLog {
 public:
  void Add(const std::string& line) {
    std::lock_guard<std::mutex> lock(mutex_);
    text_ += line + "\n";
    if (line.rfind("stage ", 0) == 0 || line.rfind("reading ", 0) == 0) stage_ = line;
  }
  std::string Text() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return text_;
  }
  // The last stage announced, for an out-of-memory error.
  std::string Stage() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stage_;
  }

 private:
  mutable std::mutex mutex_;
  std::string text_;
  std::string stage_ = "start";
};

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
  if (!app.exclude_images.empty()) {
    const std::vector<int> excluded = SelectImages(block, app.exclude_images);
    say("excluding " + std::to_string(excluded.size()) + " images (" + app.exclude_images +
        "): " + ImageNames(block, excluded));
    block = WithoutImages(block, excluded);
  }
  say(std::to_string(block.images.size()) + " images, " + std::to_string(block.cameras.size()) + " cameras, " +
      std::to_string(block.points.size()) + " tie points");
  return block;
}

// --roi in the block's local coordinates; nullopt when not given.
std::optional<RegionOfInterest> GivenRegion(const ReconstructAppSettings& app, const ImageBlock& block) {
  if (app.roi.empty()) return std::nullopt;
  RegionOfInterest roi = RegionFromNumbers(app.roi, "--roi");
  roi.min -= block.origin;
  roi.max -= block.origin;
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
  ApplySceneAndGivenOptions(preset, line);  // the options the memory check sees, before any pixel is read
  CheckRunMemory(block, *line, say);
  std::vector<std::function<void(ReconstructionOptions*)>> from_data;
  if (!OptionGiven(*line, "--radiometry")) {
    const RadiometryChoice radiometry = ChooseRadiometry(block);
    say("radiometry: " + radiometry.why);
    from_data.push_back([model = radiometry.model](ReconstructionOptions* options) { options->adjustment.radiometry = model; });
  }
  // An object's hull and outline need the background's grey level; other scenes use neither.
  if (line->options.start_closed && !OptionGiven(*line, "--hull-background")) {
    const BackgroundChoice background = ChooseBackground(block);
    say("background: " + background.why);
    from_data.push_back([background](ReconstructionOptions* options) {
      options->closed.visual_hull.foreground.background_max = background.hull_background;
      options->silhouette_foreground.background_max = background.silhouette_background;
    });
  }
  const SceneApplication applied = ApplySceneAndGivenOptions(preset, line, [&from_data](ReconstructionOptions* options) {
    for (const auto& set : from_data) set(options);
  });
  say("  the preset and the images set: " + (applied.preset.empty() ? std::string("nothing") : applied.preset));
  say("  options given: " + (applied.given.empty() ? std::string("none") : applied.given));
}

// Level images in memory while they fit the budget, else tiled on disk and read per
// window (the kept levels, float per channel).
void PlaceLevelImages(const ImageBlock& block, const ReconstructAppSettings& app, const std::string& dir,
                      ReconstructionOptions* options, const Say& say) {
  const double pyramid_mb = LevelImagesMb(block, *options);
  if (app.tiled_images || pyramid_mb > app.image_memory_mb) {
    options->image_cache_dir = (std::filesystem::path(dir) / ".image-cache").string();
    options->image_cache_mb = TileCacheMb(app.image_memory_mb);
    say("level images: " + std::to_string(static_cast<int>(pyramid_mb)) + " MB, read per window from tiled files");
  }
}

// The TIN of each level into OUT/levels/level_K.ply, and the one the wall crease step
// starts from (to replay that step without images: `facets creases`).
void KeepLevels(const std::string& out, ReconstructionOptions* options) {
  const std::filesystem::path dir = std::filesystem::path(out) / "levels";
  std::filesystem::create_directory(dir);
  auto keep = [dir](const std::string& name, const TinMesh& mesh) {
    WritePly((dir / name).string(), TinGeometryData(mesh));
  };
  options->level_done = [keep](int level, const TinMesh& mesh) {
    keep("level_" + std::to_string(level) + ".ply", mesh);
  };
  options->creases_start = [keep](int level, const TinMesh& mesh) {
    keep("level_" + std::to_string(level) + "_creases.ply", mesh);
  };
}

// The run's options beyond the bound ones: region, image placement, progress, outputs
// (into dir, the run's temporary output folder).
void PrepareRun(const ImageBlock& block, const std::string& dir, ReconstructCommandLine* line, const Say& say) {
  const ReconstructAppSettings& app = line->app;
  ReconstructionOptions& options = line->options;
  options.closed.write_start = (std::filesystem::path(dir) / "start.ply").string();
  PlaceLevelImages(block, app, dir, &options, say);
  options.roi = GivenRegion(app, block);
  options.progress = say;
  if (app.keep_levels) KeepLevels(dir, &options);
}

// Products into dir (the run's temporary output folder) and the closing lines of the log.
void WriteRunProducts(Reconstruction* reconstruction, const ImageBlock& block, const ReconstructCommandLine& line,
                      const std::string& dir, std::chrono::steady_clock::time_point start, const Say& say) {
  const ReconstructAppSettings& app = line.app;
  say("stage products: writing into " + app.out);
  ProductOptions products;
  products.glb = app.glb;
  products.vrml = app.vrml;
  products.ortho = products.dsm = products.sigma = app.rasters;
  products.preview = app.preview;
  std::string list;
  for (const auto& file : WriteProducts(reconstruction, block, dir, products)) list += " " + file;
  const Reconstruction& result = *reconstruction;
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
  std::string table = result.report.profile.Table();
  table.pop_back();  // its last newline: say adds one
  say(table);
}

// A failed or stopped run: the log beside the output folder (<out>.failed.log) and a
// message saying that the previous output is unchanged.
void ReportFailure(const std::string& out, const RunLog& log, const std::string& what) {
  const std::string log_path = out + ".failed.log";
  std::string where = "log: " + log_path;
  try {
    WriteFileAtomically(log_path, log.Text() + "error: " + what + "\n");
  } catch (const std::exception& e) {
    where = "no log written: " + std::string(e.what());
  }
  std::cerr << "facets reconstruct: error: " << what << "\nfacets reconstruct: " << out
            << " is unchanged (a previous output there stays whole); " << where << "\n";
}

// The run itself, writing into output.path().
void RunInto(const CLI::App& sub, ReconstructCommandLine* line, const std::string& dir, const Say& say) {
  const auto start = std::chrono::steady_clock::now();
  const ReconstructAppSettings& app = line->app;
  std::unique_ptr<tbb::global_control> threads;
  if (app.threads > 0) {
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, app.threads);
  }
  // Ray hits on triangle edges, and decisions that follow from them, can depend on the kernels.
  say("ray casting: " + EmbreeDevice::Shared().Describe());
  const ImageBlock read_block = ReadBlock(app, say);
  // The checks a library run makes in Reconstruct, made here before the options are chosen
  // from the block (the preset, the memory estimate and the radiometry see the images kept).
  const CheckedImageBlock checked = CheckBlock(read_block, GivenRegion(app, read_block), say);
  const ImageBlock& block = checked.block;
  ChooseOptions(block, line, say);
  WriteFileAtomically((std::filesystem::path(dir) / "settings.ini").string(), SettingsFile(sub));
  PrepareRun(block, dir, line, say);
  Reconstruction result = Reconstruct(checked, line->options);
  WriteRunProducts(&result, block, *line, dir, start, say);
}

// Everything goes into a temporary folder that replaces --out only when complete
// (io/output_folder.h); a failure or SIGINT/SIGTERM leaves --out as it was.
void RunReconstruct(const CLI::App& sub, ReconstructCommandLine* line) {
  RunLog log;
  const Say say = [&log](const std::string& text) {
    std::cout << text << "\n" << std::flush;
    log.Add(text);
  };
  const std::string& out_arg = line->app.out;
  if (!line->app.roi.empty()) RegionFromNumbers(line->app.roi, "--roi");  // before anything is written
  CheckReplaceable(out_arg, {"facets.log", "report.json", "settings.ini"});
  for (const std::string& stale : RemoveStaleTemporaryFolders(out_arg)) {
    say("removed " + stale + " (left by a run that was killed)");
  }
  OutputFolder output(out_arg, OutputFolder::Start::kEmpty);
  const std::string out = output.out();
  StopOnSignal stop([&](const std::string& signal) {
    output.Abandon();
    ReportFailure(out, log, "stopped by " + signal);
  });
  try {
    RunInto(sub, line, output.path(), say);
    stop.Finish([&] {
      WriteFileAtomically((std::filesystem::path(output.path()) / "facets.log").string(), log.Text());
      output.Commit();
      std::error_code ignored;
      std::filesystem::remove(out + ".failed.log", ignored);
    });
  } catch (const std::exception& e) {
    const bool memory = dynamic_cast<const std::bad_alloc*>(&e) != nullptr;
    stop.Finish([&] {
      output.Abandon();
      ReportFailure(out, log, memory ? OutOfMemoryMessage(log.Stage()) : output.InFinalNames(e.what()));
    });
    throw CLI::RuntimeError(1);
  }
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
    } catch (const CLI::Error&) {
      throw;  // reported already
    } catch (const std::exception& e) {
      std::cerr << "facets reconstruct: error: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace facets
