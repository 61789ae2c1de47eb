#include "apps/evaluate_command.h"

#include <chrono>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/option_binder.h"
#include "io/atomic_file.h"
#include "io/colmap_io.h"
#include "io/ply_io.h"
#include "io/project_io.h"
#include "scenes/evaluate.h"
#include "scenes/holdout.h"
#include "visibility/silhouette.h"

namespace facets {
namespace {

struct EvaluateArgs {
  std::string truth;
  std::string mesh;
  std::string json;
  bool with_samples = false;
  std::optional<double> spacing_gsd;
  std::optional<int> min_views;
  std::vector<double> roi;  // xmin ymin zmin xmax ymax zmax, empty = the truth's
  std::vector<double> principal_point_shift;  // --silhouette: dx dy pixels, empty = none
  // --silhouette: the mesh's outline in every image against the image's foreground.
  bool silhouette = false;
  std::string colmap, images, project, mask_dir;
  ForegroundOptions foreground;
  // --holdout: the mesh rendered into held-out images from the others, compared with them.
  bool holdout = false;
  bool object_coverage = false;  // --holdout: also the coverage of the foreground pixels
  HoldoutOptions holdout_options;
};

ImageBlock ReadEvaluationBlock(const EvaluateArgs& args, const std::string& mode) {
  ImageBlock block;
  if (!args.project.empty()) {
    block = ReadProject(args.project);
  } else if (!args.colmap.empty() && !args.images.empty()) {
    block = ReadColmapModel(args.colmap, args.images);
  } else {
    throw std::invalid_argument(mode + " needs --project FILE, or --colmap SPARSE_DIR and --images IMAGE_DIR");
  }
  if (!args.principal_point_shift.empty()) {
    ShiftPrincipalPoints(block, args.principal_point_shift[0], args.principal_point_shift[1]);
  }
  return block;
}

// The mesh file, checked and moved into the block's local frame (a mesh written with
// another origin than the block's is shifted by the difference).
MeshData ReadMeshInto(const ImageBlock& block, const std::string& path) {
  MeshData mesh = ReadMesh(path);
  mesh.Check(path);
  if (mesh.faces.empty()) throw std::runtime_error(path + ": has no faces: nothing to evaluate");
  const Eigen::Vector3d shift = mesh.origin - block.origin;
  for (Eigen::Vector3d& v : mesh.vertices) v += shift;
  return mesh;
}

// --roi's six values (local xmin ymin zmin xmax ymax zmax) as a box; none when not given.
std::optional<RegionOfInterest> RoiOption(const std::vector<double>& values) {
  if (values.empty()) return std::nullopt;
  return RegionFromNumbers(values, "--roi");
}

void RunHoldout(const EvaluateArgs& args) {
  const ImageBlock block = ReadEvaluationBlock(args, "--holdout");
  HoldoutOptions options = args.holdout_options;
  if (args.object_coverage) options.foreground = args.foreground;
  options.roi = RoiOption(args.roi);
  const auto start = std::chrono::steady_clock::now();
  const MeshData mesh = ReadMeshInto(block, args.mesh);
  HoldoutReport report = EvaluateHoldout(block, mesh.vertices, mesh.faces, options);
  report.mesh_name = args.mesh;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << report.Table() << "  held out: " << options.images << "\n  time " << seconds << " s\n";
  if (!args.json.empty()) {
    WriteFileAtomically(args.json, report.Json() + "\n");
    std::cout << "  json " << args.json << "\n";
  }
}

void RunSilhouette(const EvaluateArgs& args) {
  const ImageBlock block = ReadEvaluationBlock(args, "--silhouette");
  const auto start = std::chrono::steady_clock::now();
  const MeshData mesh = ReadMeshInto(block, args.mesh);
  const SilhouetteReport report =
      EvaluateSilhouettes(block, mesh.vertices, mesh.faces, args.foreground, args.mask_dir);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "silhouettes of " << args.mesh << " (background: grey <= "
            << args.foreground.background_max
            << (args.foreground.largest_component ? ", largest component" : "") << ")\n"
            << report.Table() << "\n  time " << seconds << " s\n";
  if (!args.json.empty()) {
    WriteFileAtomically(args.json, report.Json() + "\n");
    std::cout << "  json " << args.json << "\n";
  }
}


void RunEvaluate(const EvaluateArgs& args) {
  if (args.silhouette && args.holdout) throw std::invalid_argument("give --silhouette or --holdout, not both");
  if (args.silhouette) {
    RunSilhouette(args);
    return;
  }
  if (args.holdout) {
    RunHoldout(args);
    return;
  }
  if (args.truth.empty()) throw std::invalid_argument("--truth is required (or --silhouette, --holdout)");
  EvaluationOptions options;
  if (args.spacing_gsd) options.sample_spacing_gsd = *args.spacing_gsd;
  if (args.min_views) options.min_views = *args.min_views;
  if (!args.roi.empty()) {
    // A reconstruction of part of the scene is scored on that part only: truth outside
    // it would count as missing.
    options.roi = RegionFromNumbers(args.roi, "--roi");
  }
  const auto start = std::chrono::steady_clock::now();
  const EvaluationReport report = EvaluateFiles(args.truth, args.mesh, options);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << report.Table() << "\n  time                  " << seconds << " s\n";
  if (!args.json.empty()) {
    WriteFileAtomically(args.json, report.Json(args.with_samples) + "\n");
    std::cout << "  json                  " << args.json << "\n";
  }
}

}  // namespace

void AddEvaluateCommand(CLI::App& app) {
  auto args = std::make_shared<EvaluateArgs>();
  CLI::App* sub = app.add_subcommand(
      "evaluate", "score a reconstructed mesh against a rendered truth (accuracy, completeness), or against "
      "real photographs: --silhouette, --holdout");
  sub->add_option("--truth", args->truth, "truth folder written by `facets render`")
      ->check(CLI::ExistingDirectory);
  sub->add_option("--mesh", args->mesh, "reconstructed mesh (.ply or .obj)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--json", args->json, "write the report as JSON to this file");
  sub->add_flag("--samples", args->with_samples,
                "include every truth sample [x, y, z, label, views, distance] in the JSON");
  sub->add_option("--spacing", args->spacing_gsd, "sample spacing in GSD (default 1/3)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--min-views", args->min_views,
                  "images that must see a truth sample for completeness (default 1)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--roi", args->roi,
                  "score only inside xmin ymin zmin xmax ymax zmax (local; default: the truth's)")
      ->expected(6);
  sub->add_option("--principal-point-shift", args->principal_point_shift,
                  "--silhouette, --holdout: add DX DY pixels to every camera's principal point (as for reconstruct)")
      ->expected(2);
  sub->add_flag("--silhouette", args->silhouette,
                "instead: IoU of the mesh's outline and each image's foreground (needs "
                "--colmap and --images, or --project)");
  sub->add_flag("--holdout", args->holdout,
                "instead: render the mesh into held-out images from the other images and compare (ZNCC 7x7, "
                "RMS after a gain/offset fit, coverage; needs --colmap and --images, or --project)");
  sub->add_option("--holdout-images", args->holdout_options.images,
                  "--holdout: the held-out images: every-5th (the 5th, 10th, ... by name), a,b,c (names), or a "
                  "file of names; as `reconstruct --exclude-images`")
      ->capture_default_str();
  sub->add_option("--render-dir", args->holdout_options.render_dir,
                  "--holdout: write each held-out rendering as STEM_holdout.png here");
  sub->add_flag("--object-coverage", args->object_coverage,
                "--holdout: also the covered share of each image's foreground (the --silhouette foreground "
                "options)");
  sub->add_option("--colmap", args->colmap, "COLMAP text model folder (--silhouette, --holdout)")
      ->check(CLI::ExistingDirectory);
  sub->add_option("--images", args->images, "image folder of the COLMAP model (--silhouette, --holdout)")
      ->check(CLI::ExistingDirectory);
  sub->add_option("--project", args->project, "native project file (--silhouette, --holdout)")
      ->check(CLI::ExistingFile);
  sub->add_option("--background-below", args->foreground.background_max,
                  "--silhouette: grey values <= this are background")
      ->capture_default_str();
  sub->add_flag("--largest-component", args->foreground.largest_component,
                "--silhouette: the foreground is the largest 8-connected component only");
  sub->add_option("--min-component", args->foreground.min_component_pixels,
                  "--silhouette: drop foreground components of fewer pixels")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--open", args->foreground.open_radius,
                  "--silhouette: morphological opening radius (px) before the components")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--fill-holes", args->foreground.fill_holes_below,
                  "--silhouette: enclosed background holes below this many pixels are foreground")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--mask-dir", args->mask_dir,
                  "--silhouette: write one PNG per image (255 both, 170 foreground only, 85 "
                  "mesh only)");
  sub->callback([args] {
    try {
      RunEvaluate(*args);
    } catch (const std::exception& e) {
      std::cerr << "facets evaluate: error: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace facets
