// EvaluationReport as a fixed-width table for people and as JSON for scripts.
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "scenes/evaluate.h"

namespace facets {
namespace {

nlohmann::json StatsJson(const DistanceStats& s, double gsd) {
  auto block = [&](double scale) {
    return nlohmann::json{{"mean", s.mean * scale},     {"median", s.median * scale},
                          {"rms", s.rms * scale},       {"p90", s.p90 * scale},
                          {"max", s.max * scale}};
  };
  return {{"count", s.count}, {"metres", block(1.0)}, {"gsd", block(1.0 / gsd)}};
}

nlohmann::json CompletenessJson(const CompletenessStats& c, const std::vector<double>& t) {
  nlohmann::json within = nlohmann::json::object();
  for (size_t i = 0; i < t.size() && i < c.within.size(); ++i) {
    char key[32];
    std::snprintf(key, sizeof(key), "%g", t[i]);
    within[key] = c.within[i];
  }
  return {{"count", c.count}, {"within_gsd", within}};
}

// The title, inputs, GSD (m), sample spacings (m), counts and region of interest.
void AppendTableHeader(const EvaluationReport& report, std::ostringstream& out) {
  char line[512];
  out << "\nFacets evaluation report\n";
  if (!report.truth_name.empty()) out << "  truth                 " << report.truth_name << "\n";
  if (!report.mesh_name.empty()) out << "  mesh                  " << report.mesh_name << "\n";
  std::snprintf(line, sizeof(line),
                "  GSD                   %.4f m\n"
                "  sample spacing        %.4f m (reconstruction), %.4f m (truth)\n"
                "  images                %zu\n"
                "  samples               %zu reconstruction, %zu truth (%zu seen)\n",
                report.ground_pixel_size, report.sample_spacing, report.truth_sample_spacing,
                report.num_images, report.num_reconstruction_samples, report.num_truth_samples,
                report.num_truth_samples_seen);
  out << line;
  if (const auto& roi = report.roi) {
    std::snprintf(line, sizeof(line), "  region of interest    [%.3f %.3f %.3f] - [%.3f %.3f %.3f]\n",
                  roi->min.x(), roi->min.y(), roi->min.z(), roi->max.x(), roi->max.y(),
                  roi->max.z());
    out << line;
  }
}

// One accuracy row: distances in metres, then in GSD (g metres).
void AppendAccuracyRow(const std::string& name, const DistanceStats& s, double g,
                       std::ostringstream& out) {
  char line[512];
  std::snprintf(line, sizeof(line),
                "  %-18s %9zu %9.4f %9.4f %9.4f %9.4f %9.4f   %7.3f %7.3f %7.3f %7.3f\n",
                name.c_str(), s.count, s.mean, s.median, s.rms, s.p90, s.max, s.median / g,
                s.rms / g, s.p90 / g, s.max / g);
  out << line;
}

// One completeness row: the share (%) of samples within each threshold.
void AppendCompletenessRow(const std::string& name, const CompletenessStats& c,
                           std::ostringstream& out) {
  char line[512];
  std::snprintf(line, sizeof(line), "  %-18s %9zu", name.c_str(), c.count);
  out << line;
  for (double w : c.within) {
    std::snprintf(line, sizeof(line), " %9.1f %%", 100.0 * w);
    out << line;
  }
  out << "\n";
}

void AppendAccuracyTable(const EvaluationReport& report, std::ostringstream& out) {
  const double g = report.ground_pixel_size;
  char line[512];
  out << "\nAccuracy (reconstruction -> truth)             metres                          "
         "                         GSD\n";
  std::snprintf(line, sizeof(line), "  %-18s %9s %9s %9s %9s %9s %9s   %7s %7s %7s %7s\n",
                "region", "samples", "mean", "median", "rms", "p90", "max", "median", "rms",
                "p90", "max");
  out << line;
  for (const RegionScore& r : report.regions) AppendAccuracyRow(r.name, r.accuracy, g, out);
  if (report.num_images > 0) {
    out << "  by the images seeing the closest truth point\n";
    for (const RegionScore& r : report.regions) {
      if (r.label == -1) continue;
      AppendAccuracyRow(r.name + " >=2 views", r.accuracy_multi_view, g, out);
      AppendAccuracyRow(r.name + " <2 views", r.accuracy_few_views, g, out);
    }
  }
}

// Height errors (m), leaning walls (deg) and the reported sigma by view count (m).
void AppendHeightsWallsSigma(const EvaluationReport& report, std::ostringstream& out) {
  char line[512];
  const HeightErrors& heights = report.heights;
  if (heights.count > 0) {
    std::snprintf(line, sizeof(line),
                  "\nHeight errors (reconstruction - truth, highest points, %.2f m grid)\n"
                  "  points %zu (missing %zu)  rms %.4f  mean %.4f  min %.4f  max %.4f  m\n",
                  heights.spacing, heights.count, heights.missing, heights.rms, heights.mean,
                  heights.min, heights.max);
    out << line;
  }
  for (const WallLean& w : report.leaning_walls) {
    std::snprintf(line, sizeof(line),
                  "\nLeaning wall (building %d, wall %d): true lean %.2f deg (truth mesh fit %.2f), "
                  "reconstructed %.2f deg from %d vertices (plane rms %.3f m)\n",
                  w.building, w.wall, w.true_lean_deg, w.truth_fit_lean_deg, w.lean_deg, w.vertices, w.rms);
    out << line;
  }
  if (!report.sigma_by_views.empty()) {
    out << "\nReported sigma of the reconstruction's vertices by images seeing them (median / mean, m)\n";
    for (const SigmaByViews& r : report.sigma_by_views) {
      std::snprintf(line, sizeof(line),
                    "  %-10s <2 views: %6zu  %.4f / %.4f   2 views: %6zu  %.4f / %.4f   >=3 views: %6zu  %.4f / %.4f\n",
                    r.name.c_str(), r.count[0], r.median[0], r.mean[0], r.count[1], r.median[1], r.mean[1],
                    r.count[2], r.median[2], r.mean[2]);
      out << line;
    }
  }
}

}  // namespace

const RegionScore* EvaluationReport::Region(int label) const& {
  for (const RegionScore& r : regions)
    if (r.label == label) return &r;
  return nullptr;
}

const RegionScore* EvaluationReport::Region(const std::string& name) const& {
  for (const RegionScore& r : regions)
    if (r.name == name) return &r;
  return nullptr;
}

std::string EvaluationReport::Table() const {
  std::ostringstream out;
  AppendTableHeader(*this, out);
  AppendAccuracyTable(*this, out);
  out << "\nSelf-intersections of the mesh: " << mesh_crossings.pairs << " crossing triangle pairs";
  if (mesh_crossings.unchecked > 0) out << " (" << mesh_crossings.unchecked << " triangles not checked)";
  out << "\n";
  out << "\nCompleteness (truth seen by the images -> reconstruction)\n";
  std::string head = "  region              samples";
  for (double t : thresholds_gsd) {
    char h[32];
    std::snprintf(h, sizeof(h), " %7s%-4g", "<=", t);
    head += h;
  }
  out << head << "  (GSD)\n";
  for (const RegionScore& r : regions) AppendCompletenessRow(r.name, r.completeness, out);
  AppendHeightsWallsSigma(*this, out);
  out << "  by view count\n";
  for (const RegionScore& r : regions) {
    if (r.label == -1) continue;
    AppendCompletenessRow(r.name + " >=2 views", r.multi_view, out);
    AppendCompletenessRow(r.name + " <2 views", r.few_views, out);
  }
  return out.str();
}

std::string EvaluationReport::Json(bool with_samples) const {
  nlohmann::json j;
  j["ground_pixel_size"] = ground_pixel_size;
  j["sample_spacing"] = sample_spacing;
  j["truth_sample_spacing"] = truth_sample_spacing;
  j["num_images"] = num_images;
  j["num_reconstruction_samples"] = num_reconstruction_samples;
  j["num_truth_samples"] = num_truth_samples;
  j["num_truth_samples_seen"] = num_truth_samples_seen;
  j["thresholds_gsd"] = thresholds_gsd;
  if (!truth_name.empty()) j["truth"] = truth_name;
  if (!mesh_name.empty()) j["mesh"] = mesh_name;
  j["mesh_crossing_pairs"] = mesh_crossings.pairs;
  j["mesh_unchecked_triangles"] = mesh_crossings.unchecked;
  if (roi) {
    j["region_of_interest"] = {{"min", {roi->min.x(), roi->min.y(), roi->min.z()}},
                               {"max", {roi->max.x(), roi->max.y(), roi->max.z()}}};
  }
  nlohmann::json regions_json = nlohmann::json::array();
  for (const RegionScore& r : regions) {
    regions_json.push_back({{"label", r.label},
                            {"name", r.name},
                            {"accuracy", StatsJson(r.accuracy, ground_pixel_size)},
                            {"accuracy_multi_view", StatsJson(r.accuracy_multi_view, ground_pixel_size)},
                            {"accuracy_few_views", StatsJson(r.accuracy_few_views, ground_pixel_size)},
                            {"completeness", CompletenessJson(r.completeness, thresholds_gsd)},
                            {"completeness_multi_view",
                             CompletenessJson(r.multi_view, thresholds_gsd)},
                            {"completeness_few_views",
                             CompletenessJson(r.few_views, thresholds_gsd)}});
  }
  j["regions"] = regions_json;
  j["height_errors"] = {{"count", heights.count}, {"missing", heights.missing},
                        {"rms", heights.rms},     {"mean", heights.mean},
                        {"min", heights.min},     {"max", heights.max},
                        {"spacing", heights.spacing}};
  for (const SigmaByViews& r : sigma_by_views) {
    nlohmann::json row = {{"label", r.label}, {"name", r.name}};
    const char* keys[3] = {"views_lt2", "views_2", "views_ge3"};
    for (int g = 0; g < 3; ++g) {
      row[keys[g]] = {{"count", r.count[g]}, {"median", r.median[g]}, {"mean", r.mean[g]}};
    }
    j["sigma_by_views"].push_back(row);
  }
  for (const WallLean& w : leaning_walls) {
    j["leaning_walls"].push_back(
        {{"building", w.building}, {"wall", w.wall}, {"true_lean_deg", w.true_lean_deg},
         {"truth_fit_lean_deg", w.truth_fit_lean_deg},
         {"lean_deg", std::isfinite(w.lean_deg) ? nlohmann::json(w.lean_deg) : nlohmann::json(nullptr)},
         {"vertices", w.vertices}, {"rms", w.rms}});
  }
  if (with_samples) {
    nlohmann::json s = nlohmann::json::array();
    for (const TruthSample& t : truth_samples) {
      s.push_back({t.point.x(), t.point.y(), t.point.z(), t.label, t.views, t.distance});
    }
    j["truth_samples"] = s;  // [x, y, z, label, views, distance]
  }
  return j.dump(2);
}

}  // namespace facets
