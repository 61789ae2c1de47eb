// ReadTruthScene: the truth folder written by `facets render` (truth.json, truth.ply or
// truth.obj, sparse/).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "io/colmap_io.h"
#include "io/input_file.h"
#include "scenes/evaluate.h"

namespace facets {
namespace {

// truth.json "region_of_interest": {"min": [x, y, z], "max": [x, y, z]} (local, m).
RegionOfInterest ReadTruthRoi(const nlohmann::json& r, const std::string& json_path) {
  RegionOfInterest roi;
  const auto lo = r.at("min").get<std::vector<double>>();
  const auto hi = r.at("max").get<std::vector<double>>();
  if (lo.size() != 3 || hi.size() != 3) {
    throw std::runtime_error(json_path + ": region_of_interest min/max need 3 values");
  }
  roi.min = Eigen::Vector3d(lo[0], lo[1], lo[2]);
  roi.max = Eigen::Vector3d(hi[0], hi[1], hi[2]);
  if (!roi.min.allFinite() || !roi.max.allFinite() ||
      !(roi.min.array() <= roi.max.array()).all()) {
    throw std::runtime_error(json_path + ": region_of_interest is empty or not finite");
  }
  return roi;
}

// The "building" entries of truth.json "shapes" (centre m, azimuth deg, sizes m, the
// outward lean of each wall deg); other shapes are skipped.
std::vector<TruthBuilding> ReadTruthBuildings(const nlohmann::json& shapes,
                                              const std::string& json_path) {
  std::vector<TruthBuilding> buildings;
  for (const auto& shape : shapes) {
    if (shape.value("type", "") != "building") continue;
    TruthBuilding b;
    const auto c = shape.value("centre", std::vector<double>{0, 0, 0});
    if (c.size() != 3) throw std::runtime_error(json_path + ": building centre needs 3 values");
    b.centre = Eigen::Vector3d(c[0], c[1], c[2]);
    b.azimuth_deg = shape.value("azimuth_deg", 0.0);
    b.length = shape.value("length", 10.0);
    b.width = shape.value("width", 10.0);
    b.height = shape.value("height", 3.0);
    const auto lean = shape.value("wall_lean_deg", std::vector<double>{0, 0, 0, 0});
    if (lean.size() != 4) throw std::runtime_error(json_path + ": wall_lean_deg needs 4 values");
    b.wall_lean_deg = Eigen::Vector4d(lean[0], lean[1], lean[2], lean[3]);
    buildings.push_back(b);
  }
  return buildings;
}

// truth.json "labels": {"0": "ground", ...}, keys integers.
void ReadTruthLabels(const nlohmann::json& labels, const std::string& json_path,
                     std::map<int, std::string>* names) {
  for (const auto& [key, value] : labels.items()) {
    int label = 0;
    try {
      size_t used = 0;
      label = std::stoi(key, &used);
      if (used != key.size()) throw std::invalid_argument(key);
    } catch (const std::exception&) {
      throw std::runtime_error(json_path + ": label key '" + key + "' is not an integer");
    }
    (*names)[label] = value.get<std::string>();
  }
}

// truth.json: the GSD (m, required), region of interest, buildings and label names.
void ReadTruthJson(const std::string& json_path, TruthScene* truth) {
  std::ifstream json_in = OpenInputFile(json_path, "truth description");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(json_in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(json_path + ": not valid JSON: " + e.what());
  }
  try {
    if (!j.contains("ground_pixel_size")) {
      throw std::runtime_error(json_path + ": missing \"ground_pixel_size\"");
    }
    truth->ground_pixel_size = j.at("ground_pixel_size").get<double>();
    if (!(truth->ground_pixel_size > 0) || !std::isfinite(truth->ground_pixel_size)) {
      throw std::runtime_error(json_path + ": \"ground_pixel_size\" must be > 0");
    }
    if (j.contains("region_of_interest") && !j["region_of_interest"].is_null()) {
      truth->roi = ReadTruthRoi(j["region_of_interest"], json_path);
    }
    if (j.contains("shapes") && j["shapes"].is_array()) {
      truth->buildings = ReadTruthBuildings(j["shapes"], json_path);
    }
    if (j.contains("labels")) ReadTruthLabels(j["labels"], json_path, &truth->labels);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(json_path + ": " + e.what());
  }
}

}  // namespace

TruthScene ReadTruthScene(const std::string& dir) {
  namespace fs = std::filesystem;
  TruthScene truth;
  const fs::path root(dir);
  if (!fs::is_directory(root)) throw std::runtime_error(dir + ": truth folder does not exist");
  ReadTruthJson((root / "truth.json").string(), &truth);
  const fs::path ply = root / "truth.ply";
  const fs::path obj = root / "truth.obj";
  truth.mesh = fs::exists(ply) || !fs::exists(obj) ? ReadPly(ply.string()) : ReadObj(obj.string());
  truth.block = ReadColmapModel((root / "sparse").string());
  return truth;
}

}  // namespace facets
