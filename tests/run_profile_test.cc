// The run's profile in report.json (engine/pipeline/run_profile.h): a reconstruction of
// the seed gable roof with the aerial preset (every stage of the aerial path runs: the
// searches, the trials, the wall corners on the last pass) written as `facets
// reconstruct` writes it, report.json read back. Checked: its structure, not the clocks'
// values: every stage on every pass over a level and the run's own stages present, once
// each, every second non-negative, the stages' CPU and wall seconds summing to no more
// than the run's total, the window phases and the categories present.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/pipeline/products.h"
#include "engine/pipeline/reconstruction.h"
#include "engine/pipeline/scene_preset.h"
#include "io/colmap_io.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"

namespace facets {
namespace {
namespace fs = std::filesystem;

nlohmann::json ReconstructAndReadReport(const std::string& dir) {
  const Scene scene = LoadScene(std::string(FACETS_SOURCE_DIR) + "/scenes/data/seed_gable_parallel.json");
  RenderScene(scene, dir + "/scene");
  ImageBlock block = ReadColmapModel(dir + "/scene/sparse", dir + "/scene/images");
  block.roi = scene.roi;
  ReconstructionOptions options;
  ApplyScenePreset(ScenePreset::kAerial, &options);
  options.levels = 3;
  Reconstruction r = Reconstruct(block, options);
  const std::string out = dir + "/products";
  fs::remove_all(out);
  WriteProducts(&r, block, out, ProductOptions{});
  std::ifstream in(out + "/report.json");
  return nlohmann::json::parse(in);
}

TEST(RunProfile, ReportHasEveryStageWithSecondsWithinTheRunTotal) {
  const nlohmann::json report = ReconstructAndReadReport(testing::TempDir() + "/facets_run_profile");
  ASSERT_TRUE(report.contains("profile"));
  const nlohmann::json& profile = report["profile"];
  const double total_cpu = profile["total"]["cpu_seconds"].get<double>();
  const double total_wall = profile["total"]["wall_seconds"].get<double>();
  EXPECT_GT(total_cpu, 0.0);
  EXPECT_GT(total_wall, 0.0);

  // (level, cycle) -> stages; the run's own stages at level -1.
  std::map<std::pair<int, int>, std::set<std::string>> stages;
  double stages_cpu = 0.0, stages_wall = 0.0;
  long long window_runs = 0;
  for (const nlohmann::json& e : profile["entries"]) {
    EXPECT_GE(e["cpu_seconds"].get<double>(), 0.0) << e.dump();
    EXPECT_GE(e["wall_seconds"].get<double>(), 0.0) << e.dump();
    EXPECT_GE(e["calls"].get<int>(), 1) << e.dump();
    if (e.contains("window_thread_cpu_seconds")) {
      for (const auto& [phase, value] : e["window_thread_cpu_seconds"].items()) {
        EXPECT_GE(value.get<double>(), 0.0) << phase;
      }
    }
    if (e.contains("part")) continue;
    const std::pair<int, int> pass(e["level"].get<int>(), e["cycle"].get<int>());
    EXPECT_TRUE(stages[pass].insert(e["stage"].get<std::string>()).second) << e.dump();
    stages_cpu += e["cpu_seconds"].get<double>();
    stages_wall += e["wall_seconds"].get<double>();
    if (e.contains("window_thread_cpu_seconds")) window_runs += e["window_thread_cpu_seconds"]["runs"].get<long long>();
  }
  EXPECT_LE(stages_cpu, total_cpu + 1e-9);
  EXPECT_LE(stages_wall, total_wall + 1e-9);
  EXPECT_NEAR(profile["stages_cpu_seconds"].get<double>(), stages_cpu, 1e-9);
  EXPECT_GT(window_runs, 0);

  const std::set<std::string> run_stages = {"start", "images", "products"};
  const std::pair<int, int> run_own(-1, 0);
  EXPECT_EQ(stages[run_own], run_stages);
  // The passes in report.json's order: the descent 2, 1, 0, then the preset's V-cycle.
  std::vector<std::pair<int, int>> passes;
  for (const nlohmann::json& level : report["levels"]) {
    passes.emplace_back(level["level"].get<int>(), level.value("cycle", 0));
  }
  ASSERT_GE(passes.size(), 3u);
  EXPECT_EQ(stages.size(), passes.size() + 1);
  for (size_t k = 0; k < passes.size(); ++k) {
    std::set<std::string> expected = {"search before", "adjust", "search rounds", "straighten",
                                      "relax unseen",  "lips",   "validity"};
    // A pass starts by descending from the pass before, or (a V-cycle's first) by going back up.
    if (k > 0) expected.insert(passes[k].second != passes[k - 1].second ? "back up" : "descent");
    if (k + 1 == passes.size()) expected.insert("wall corners");
    EXPECT_EQ(stages[passes[k]], expected) << "pass " << k;
  }

  for (const char* name : {"images", "start", "descent", "prepare", "cast", "linearise", "solve", "update",
                                  "finish", "normal search", "plane propagation", "trial re-adjustment",
                                  "crossing counts", "untangling", "products"}) {
    ASSERT_TRUE(profile["categories"].contains(name)) << name;
    const double cpu = profile["categories"][name]["cpu_seconds"].get<double>();
    EXPECT_GE(cpu, 0.0) << name;
    EXPECT_LE(cpu, total_cpu + 1e-9) << name;
  }
}

}  // namespace
}  // namespace facets
