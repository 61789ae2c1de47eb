#include "apps/export_command.h"

#include <Eigen/Core>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "apps/stop_on_signal.h"
#include "io/output_folder.h"
#include "io/ply_io.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

// The finest level's ground pixel from the run's report.json (levels are in processing
// order, the finest last).
double FinestGroundPixel(const fs::path& report_path) {
  std::ifstream in(report_path);
  if (!in) {
    throw std::runtime_error(report_path.string() +
                             ": missing (needed for the raster pixel; or give --raster-pixel)");
  }
  nlohmann::json report;
  try {
    in >> report;
  } catch (const std::exception& e) {
    throw std::runtime_error(report_path.string() + ": not valid JSON: " + e.what());
  }
  const auto levels = report.find("levels");
  if (levels == report.end() || !levels->is_array() || levels->empty() ||
      !levels->back().contains("ground_pixel") || !levels->back()["ground_pixel"].is_number()) {
    throw std::runtime_error(report_path.string() +
                             ": no levels[].ground_pixel (incomplete run; give --raster-pixel)");
  }
  const double pixel = levels->back()["ground_pixel"].get<double>();
  if (!(pixel > 0.0)) throw std::runtime_error(report_path.string() + ": ground_pixel is not positive");
  return pixel;
}

// The preview's up of a facade (ReconstructionReport::camera_up) from the run's
// report.json; Z when the file or the entry is missing (runs before it was written).
Eigen::Vector3d CameraUp(const fs::path& report_path) {
  std::ifstream in(report_path);
  if (!in) return Eigen::Vector3d::UnitZ();
  nlohmann::json report;
  try {
    in >> report;
  } catch (const std::exception& e) {
    throw std::runtime_error(report_path.string() + ": not valid JSON: " + e.what());
  }
  const auto up = report.find("camera_up");
  if (up == report.end()) return Eigen::Vector3d::UnitZ();
  if (!up->is_array() || up->size() != 3 || !(*up)[0].is_number() || !(*up)[1].is_number() ||
      !(*up)[2].is_number()) {
    throw std::runtime_error(report_path.string() + ": camera_up is not 3 numbers");
  }
  return {(*up)[0].get<double>(), (*up)[1].get<double>(), (*up)[2].get<double>()};
}

}  // namespace

std::vector<std::string> RunExport(const ExportArgs& args) {
  ProductOptions options;
  options.SetFormats(args.formats);
  options.raster_pixel = args.raster_pixel;
  options.Check();
  const fs::path run(args.run_dir);
  if (!fs::is_directory(run)) throw std::runtime_error(args.run_dir + ": no such run folder");
  const fs::path surface_path = run / "surface.ply";
  if (!fs::exists(surface_path)) {
    throw std::runtime_error(surface_path.string() +
                             ": missing: not a finished `facets reconstruct` run folder");
  }
  ProductSurface surface = ProductSurfaceFromMesh(ReadPly(surface_path.string()), surface_path.string());
  if (!args.crs.empty()) surface.crs = args.crs;
  if (options.preview) surface.up = CameraUp(run / "report.json");
  if (options.AnyRaster() && options.raster_pixel <= 0.0) {
    surface.default_raster_pixel = FinestGroundPixel(run / "report.json");
  }
  if (options.sigma && surface.sigma.empty()) {
    throw std::runtime_error(surface_path.string() +
                             ": has no sigma per vertex (leave sigma out of --formats)");
  }
  for (const std::string& stale : RemoveStaleTemporaryFolders(args.out)) {
    std::cout << "facets export: removed " << stale << " (left by a run that was killed)\n";
  }
  OutputFolder output(args.out, OutputFolder::Start::kPreviousFiles);
  StopOnSignal stop([&output](const std::string& signal) {
    output.Abandon();
    std::cerr << "facets export: stopped by " << signal << "; " << output.out() << " is unchanged\n";
  });
  try {
    const std::vector<std::string> written = WriteSurfaceProducts(surface, output.path(), options);
    stop.Finish([&output] { output.Commit(); });
    return written;
  } catch (const std::exception& e) {
    throw std::runtime_error(output.InFinalNames(e.what()));
  }
}

void AddExportCommand(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* sub = app.add_subcommand("export", "re-export the products of a finished reconstruct run");
  sub->add_option("run_dir", args->run_dir, "output folder of `facets reconstruct`")->required();
  sub->add_option("--out", args->out, "folder for the products (may be the run folder)")->required();
  sub->add_option("--formats", args->formats, std::string("comma-separated: ") + kFormatNames)
      ->capture_default_str();
  sub->add_option("--raster-pixel", args->raster_pixel,
                  "ground pixel of ortho/dsm/sigma (m); 0 = the run's finest level")
      ->capture_default_str();
  sub->add_option("--crs", args->crs, "CRS of the products (e.g. EPSG:25832); default: the run's");
  sub->callback([args] {
    try {
      const std::vector<std::string> files = RunExport(*args);
      std::string list;
      for (const auto& f : files) list += " " + f;
      std::cout << "facets export: written into " << args->out << ":" << list << "\n";
    } catch (const std::exception& e) {
      std::cerr << "facets export: error: " << e.what() << "\nfacets export: " << args->out
                << " is unchanged\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace facets
