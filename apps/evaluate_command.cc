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

#include "io/atomic_file.h"
#include "scenes/evaluate.h"

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
};


void RunEvaluate(const EvaluateArgs& args) {
  EvaluationOptions options;
  if (args.spacing_gsd) options.sample_spacing_gsd = *args.spacing_gsd;
  if (args.min_views) options.min_views = *args.min_views;
  if (!args.roi.empty()) {
    // A reconstruction of part of the scene is scored on that part only: truth outside
    // it would count as missing.
    RegionOfInterest roi;
    roi.min = Eigen::Vector3d(args.roi[0], args.roi[1], args.roi[2]);
    roi.max = Eigen::Vector3d(args.roi[3], args.roi[4], args.roi[5]);
    if (!(roi.max.array() > roi.min.array()).all()) {
      throw std::invalid_argument("--roi: every max must exceed its min");
    }
    options.roi = roi;
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
      "evaluate", "score a reconstructed mesh against a rendered truth: accuracy, completeness");
  sub->add_option("--truth", args->truth, "truth folder written by `facets render`")
      ->required()
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
