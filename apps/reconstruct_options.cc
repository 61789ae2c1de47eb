#include "apps/reconstruct_options.h"

#include <memory>
#include <sstream>

#include "apps/option_binder.h"
#include "apps/reconstruct_expert_options.h"

namespace facets {
namespace {

constexpr const char* kExpertGroup = "Expert";

// CLI11's formatter, but the group Expert only with --help-all, and negated flags
// without their "{false}".
class ReconstructHelpFormatter : public CLI::Formatter {
 public:
  std::string make_help(const CLI::App* app, std::string name, CLI::AppFormatMode mode) const override {
    if (mode == CLI::AppFormatMode::Sub) return make_expanded(app);
    std::ostringstream out;
    out << make_description(app) << make_usage(app, name) << make_positionals(app);
    for (const std::string& group : app->get_groups()) {
      if (group.empty() || (group == kExpertGroup && mode != CLI::AppFormatMode::All)) continue;
      const std::vector<const CLI::Option*> options = app->get_options(
          [&group](const CLI::Option* option) { return option->get_group() == group && option->nonpositional(); });
      if (!options.empty()) out << make_group(group, false, options) << "\n";
    }
    out << make_subcommands(app, mode) << '\n' << make_footer(app);
    return out.str();
  }
  std::string make_option_name(const CLI::Option* option, bool positional) const override {
    std::string name = CLI::Formatter::make_option_name(option, positional);
    for (size_t at = name.find("{false}"); at != std::string::npos; at = name.find("{false}")) name.erase(at, 7);
    return name;
  }
};

void BindInput(const OptionBinder& bind, ReconstructAppSettings& app, ReconstructionOptions& options) {
  bind.Value("--colmap", app.colmap, "COLMAP text model folder (cameras.txt, images.txt, points3D.txt)");
  bind.Value("--images", app.images, "image folder of the COLMAP model");
  bind.Value("--project", app.project, "native project file (JSON), instead of --colmap and --images");
  bind.Value("--principal-point-shift", app.principal_point_shift,
             "add DX DY pixels to every camera's principal point: a calibration whose top-left pixel centre is "
             "(0, 0) (e.g. Middlebury's K matrices) needs 0.5 0.5")
      ->expected(2);
  bind.Value("--exclude-images", app.exclude_images,
             "leave these images out, e.g. to judge the surface by them later with `facets evaluate --holdout`: "
             "every-5th (the 5th, 10th, ... by name), a,b,c (names), or a file of names (one a line)");
  bind.Engine().Value("--start-mesh", options.closed.mesh_file,
                               "start from this closed (or any) mesh, PLY or OBJ, local coordinates");
}

void BindRegion(const OptionBinder& bind, ReconstructAppSettings& app, ReconstructionOptions& options) {
  bind.Value("--roi", app.roi, "region of interest: xmin ymin zmin xmax ymax zmax (global coordinates, m)")
      ->expected(6);
  bind.Engine().Value("--start-height", options.start_height,
                               "start from a plane at this height (local Z, m); default: tie points or their "
                               "median height");
}

void BindQuality(const OptionBinder& bind, ReconstructAppSettings& app, ReconstructionOptions& options) {
  bind.Choice("--scene", app.scene,
              {{"auto", ScenePreset::kAuto},
               {"aerial", ScenePreset::kAerial},
               {"facade", ScenePreset::kFacade},
               {"object", ScenePreset::kObject}},
              "what the images show: aerial (nadir and oblique over buildings: walls refined), facade (from the "
              "street), object (all around); auto: chosen from the cameras and tie points. Options given set "
              "over the preset");
  const OptionBinder engine = bind.Engine();
  engine.Value("--levels", options.levels, "image pyramid levels (1 = the original images only)")
      ->check(CLI::Range(1, 20));
  engine.Value("--finest-level", options.finest_level,
               "last adjusted pyramid level (0 = the original images; K: products at 2^K times their ground "
               "pixel)")
      ->check(CLI::Range(0, 20));
  engine.Choice("--radiometry", options.adjustment.radiometry,
                {{"none", RadiometricModel::kNone},
                 {"constant", RadiometricModel::kConstant},
                 {"linear", RadiometricModel::kLinear}},
                "grey-value offset (constant) and scale (linear) per image; not given: chosen from the tie "
                "points' brightness in each image (printed): linear where the exposure differs");
  engine.Switch("--colour", options.colour, "one grey value per colour channel (geometry shared)");
  engine.Value("--lambda", options.adjustment.lambda, "weight of the curvature regularisation (docs/ENGINE.md)");
  engine.Value("--facet-pixels", options.facet_pixels,
               "edge of a grey facet in pixels of each level (a triangle edge is 4 facets)");
  engine.Value("--max-iterations", options.adjustment.max_iterations, "most iterations per window and level");
}

void BindProducts(const OptionBinder& bind, ReconstructAppSettings& app) {
  bind.Value("--out", app.out, "output folder")
      ->required()
      ->check(CLI::Validator(
          [](const std::string& folder) { return folder.empty() ? std::string("the output folder is empty") : ""; },
          "FOLDER"));
  bind.Negative("--no-glb", app.glb, "do not write surface.glb");
  bind.Negative("--no-vrml", app.vrml, "do not write surface.wrl");
  bind.Negative("--no-rasters", app.rasters, "do not write ortho.tif, dsm.tif, sigma.tif");
  bind.Negative("--no-preview", app.preview, "do not write preview.png");
  bind.Switch("--keep-levels", app.keep_levels,
              "also write each level's TIN as levels/level_K.ply (K = pyramid level), and the TIN the wall "
              "crease step starts from as levels/level_K_creases.ply");
}

void BindPerformance(const OptionBinder& bind, ReconstructAppSettings& app) {
  bind.Value("--threads", app.threads, "threads (0 = all cores)")->check(CLI::NonNegativeNumber);
  bind.Value("--image-memory", app.image_memory_mb, "MB for level images in memory; more goes to tiled files")
      ->check(CLI::PositiveNumber);
  bind.Switch("--tiled-images", app.tiled_images, "level images on disk, read per window, whatever their size");
}

// The options' current values, by option (capture_default_str reads the bound field).
std::vector<std::string> CurrentValues(const std::vector<CLI::Option*>& options) {
  std::vector<std::string> values;
  for (CLI::Option* option : options) values.push_back(option->capture_default_str()->get_default_str());
  return values;
}

}  // namespace

void BindReconstructOptions(CLI::App* sub, ReconstructCommandLine* line) {
  auto formatter = std::make_shared<ReconstructHelpFormatter>();
  formatter->column_width(36);
  sub->formatter(formatter);
  const OptionBinder bind(sub, &line->engine_options);
  BindInput(bind.InGroup("Input"), line->app, line->options);
  BindRegion(bind.InGroup("Region"), line->app, line->options);
  BindQuality(bind.InGroup("Quality"), line->app, line->options);
  BindProducts(bind.InGroup("Products"), line->app);
  BindPerformance(bind.InGroup("Performance"), line->app);
  BindExpertOptions(bind.InGroup(kExpertGroup).Engine(), line->options);
  sub->footer(
      "--config FILE (before or after `reconstruct`): options as `key = value` lines in a [reconstruct] "
      "section, as in the settings.ini each run writes; an unknown key is an error; the command line wins.\n"
      "--help-all: also the expert options (each can be set in the --config file too).");
}

bool OptionGiven(const ReconstructCommandLine& line, const std::string& name) {
  for (const CLI::Option* option : line.engine_options) {
    if (option->check_name(name)) return option->count() > 0;
  }
  return false;
}

SceneApplication ApplySceneAndGivenOptions(ScenePreset preset, ReconstructCommandLine* line,
                                           const std::function<void(ReconstructionOptions*)>& from_data) {
  const std::vector<CLI::Option*>& bound = line->engine_options;
  const ReconstructionOptions library_defaults;
  line->options = library_defaults;  // a copy: GCC 12 warns falsely on moving from a temporary
  const std::vector<std::string> defaults = CurrentValues(bound);
  ApplyScenePreset(preset, &line->options);
  if (from_data) from_data(&line->options);
  const std::vector<std::string> preset_values = CurrentValues(bound);
  // Options given (on the command line or in the --config file) set their fields again.
  for (CLI::Option* option : bound) {
    if (option->count() > 0) option->run_callback();
  }
  const std::vector<std::string> values = CurrentValues(bound);
  SceneApplication applied;
  for (size_t i = 0; i < bound.size(); ++i) {
    const std::string key = bound[i]->get_single_name();
    if (preset_values[i] != defaults[i]) {
      applied.preset += (applied.preset.empty() ? "" : ", ") + key + "=" + preset_values[i];
    }
    if (bound[i]->count() > 0) applied.given += (applied.given.empty() ? "" : ", ") + key + "=" + values[i];
  }
  return applied;
}

std::string SettingsFile(const CLI::App& sub) {
  std::ostringstream file;
  file << "# every option of a facets reconstruct run: facets reconstruct --config settings.ini --out OTHER\n"
       << "[reconstruct]\n";
  for (const CLI::Option* option : sub.get_options()) {
    if (!option->get_configurable() || option->get_single_name().empty()) continue;
    CLI::Option* bound = const_cast<CLI::Option*>(option);  // capture_default_str only reads the field
    const std::string value = bound->capture_default_str()->get_default_str();
    if (value.empty()) continue;
    // A list option's value is CLI11's "[a,b,...]"; a single value that starts with '['
    // (a path, say) is quoted like any other, or it would read back as a list.
    const bool list = option->get_items_expected_max() > 1 && value.front() == '[';
    file << option->get_single_name() << "=" << (list ? value : CLI::detail::convert_arg_for_ini(value)) << "\n";
  }
  return file.str();
}

}  // namespace facets
