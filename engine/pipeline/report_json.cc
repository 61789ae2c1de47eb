// ReconstructionReport as report.json and as one progress line.
#include <nlohmann/json.hpp>

#include <cmath>
#include <sstream>

#include "engine/pipeline/reconstruction.h"

namespace facets {
namespace {

using nlohmann::json;

json IterationJson(const IterationReport& it) {
  return {{"iteration", it.iteration},
          {"observations", it.observations},
          {"rays", it.rays},
          {"rect_pixels", it.rect_pixels},
          {"cg_iterations", it.cg_iterations},
          {"step_scale", it.step_scale},
          {"sigma0", it.sigma0},
          {"robust_scale", it.robust_scale},
          {"rejected", it.rejected},
          {"silhouette_observations", it.silhouette},
          {"silhouette_outside", it.silhouette_outside},
          {"max_dn", {it.max_dn_interior, it.max_dn_border, it.max_dn_corner}},
          {"fold_limited", it.fold_limited},
          {"seconds",
           {{"cast", it.seconds_cast},
            {"linearise", it.seconds_linearise},
            {"solve", it.seconds_solve},
            {"update", it.seconds_update}}}};
}

json WindowJson(const WindowReport& w) {
  const long long judged = w.observations + w.rejected;
  json window = {{"converged", w.converged},
                 {"stalled", w.stalled},
                 {"iterations", w.iterations.size()},
                 {"cg_iterations", w.cg_iterations_total},
                 {"observations", w.observations},
                 {"pseudo_observations", w.pseudo_observations},
                 {"background_pixels", w.background},
                 {"rejected", w.rejected},
                 {"rejected_share", judged > 0 ? static_cast<double>(w.rejected) / judged : 0.0},
                 {"downweighted", w.downweighted},
                 {"silhouette_observations", w.silhouette},
                 {"silhouette_outside", w.silhouette_outside},
                 {"unknowns", w.unknowns},
                 {"redundancy", w.redundancy},
                 {"sigma0", w.sigma0},
                 {"crease_edges", w.crease_edges},
                 {"crease_passes_dropped", w.crease_passes_dropped},
                 {"crease_pass_iterations_dropped", w.crease_pass_iterations_dropped},
                 {"seconds", w.seconds_total},
                 {"seconds_precision", w.seconds_precision},
                 {"precision_computed", w.precision_computed},
                 {"residual_rho_x", w.residual_rho_x},
                 {"residual_rho_y", w.residual_rho_y},
                 {"variance_factor", w.variance_factor}};
  for (const auto& it : w.iterations) window["per_iteration"].push_back(IterationJson(it));
  return window;
}

// The searches before the level and the V-cycle's projection, when they ran.
void AddSearchJson(const LevelReport& level, json* l) {
  (*l)["normal_search_rounds"] = level.normal_search_rounds;
  if (level.normal_search_local_windows > 0) (*l)["normal_search_local_windows"] = level.normal_search_local_windows;
  if (level.cycle > 0) {
    const ProjectionReport& p = level.projection;
    (*l)["cycle"] = level.cycle;
    (*l)["v_cycle_projection"] = {{"moved", p.moved},
                                  {"missed", p.missed},
                                  {"limited", p.limited},
                                  {"median_move", p.median_move},
                                  {"max_move", p.max_move}};
  }
  const NormalSearchReport& ns = level.normal_search;
  if (ns.searched > 0) {
    (*l)["normal_search"] = {{"searched", ns.searched},       {"peaks", ns.peaks},
                             {"moved", ns.moved},             {"limited", ns.limited},
                             {"median_move", ns.median_move}, {"max_move", ns.max_move}};
  }
  const PlanePropagationReport& pp = level.plane_propagation;
  if (pp.sources + pp.targets > 0) {
    (*l)["plane_propagation"] = {{"sources", pp.sources},         {"targets", pp.targets},
                                 {"hypotheses", pp.hypotheses},   {"moved", pp.moved},
                                 {"limited", pp.limited},         {"iterations", pp.iterations},
                                 {"median_move", pp.median_move}, {"max_move", pp.max_move}};
  }
}

// Validity and the refinement stages' counts.
void AddRefinementJson(const LevelReport& level, json* l) {
  json& j = *l;
  j["folded_faces"] = level.folded_faces;
  j["hull_clamped"] = level.hull_clamped;
  j["hull_unresolved"] = level.hull_unresolved;
  j["hull_rim_pushed"] = level.hull_rim_pushed;
  j["self_intersections"] = level.self_intersections;
  j["fold_limited"] = level.fold_limited;
  j["relaxed_unseen"] = level.relaxed;
  j["lips_folded"] = level.lips_folded;
  j["lip_vertices_moved"] = level.lip_vertices_moved;
  j["lips_dropped"] = level.lips_dropped;
  j["corner_splits"] = level.corner_splits;
  j["corners_found"] = level.corners_found;
  j["corners_laid"] = level.corners_laid;
  j["feet_found"] = level.feet_found;
  j["feet_laid"] = level.feet_laid;
  j["eaves_found"] = level.eaves_found;
  j["eaves_laid"] = level.eaves_laid;
  j["corner_vertices_moved"] = level.corner_vertices_moved;
  j["corners_dropped"] = level.corners_dropped;
  j["lips_untangled"] = level.lips_untangled;
  j["lips_flattened"] = level.lips_flattened;
  j["crossing_pairs_untangled"] = level.crossing_untangled;
  j["untangle_moved_vertices"] = level.untangle_moved;
  j["untangle_membranes"] = level.untangle_membranes;
  j["straighten_passes_kept"] = level.straighten_kept;
  j["straighten_passes_dropped"] = level.straighten_dropped;
  j["straightened_vertices"] = level.straightened;
}

json LevelJson(const LevelReport& level) {
  json l;
  l["level"] = level.level;
  l["ground_pixel"] = level.ground_pixel;
  l["edge_length"] = level.edge_length;
  l["smoothed"] = level.smoothed;
  AddSearchJson(level, &l);
  l["break_off"] = level.break_off;
  l["vertices"] = level.vertices;
  l["faces"] = level.faces;
  l["seconds"] = level.seconds;
  AddRefinementJson(level, &l);
  l["summary"] = WindowJson(level.window);
  l["summary"].erase("per_iteration");
  l["window_groups"] = level.window_groups;
  for (size_t k = 0; k < level.windows.size(); ++k) {
    json window = WindowJson(level.windows[k]);
    window["window"] = k;
    if (k < level.window_core_faces.size()) window["core_faces"] = level.window_core_faces[k];
    l["windows"].push_back(window);
  }
  return l;
}

json StartJson(const ReconstructionReport& report) {
  json j;
  j["start_height"] = report.start_height;
  j["start_surface"] = report.start_surface;
  j["camera_up"] = {report.camera_up.x(), report.camera_up.y(), report.camera_up.z()};
  if (!report.start_detail.empty()) j["start_detail"] = report.start_detail;
  j["seconds_total"] = report.seconds_total;
  j["seconds_images"] = report.seconds_images;
  j["images_cached"] = report.images_cached;
  const FacetCrossingRepair& fc = report.facet_crossings;
  if (fc.pairs_found >= 0) {
    j["facet_crossings"] = {{"pairs_found", fc.pairs_found},         {"pairs_left", fc.pairs_left},
                            {"rounds", fc.rounds},                   {"tin_faces_changed", fc.faces_changed},
                            {"tin_vertices_weighted", fc.vertices_weighted},
                            {"unchecked_facets", fc.unchecked_facets}, {"max_node_move", fc.max_move}};
  }
  for (const auto& t : report.lifting) {
    j["object_lifting"].push_back(
        {{"height", t.height}, {"sigma0", t.sigma0}, {"mean_dn", t.mean_dn}, {"observations", t.observations}});
  }
  return j;
}

json WindowClocksJson(const WindowClocks& w) {
  return {{"runs", w.runs},           {"iterations", w.iterations}, {"prepare", w.prepare},
          {"occluders", w.occluders},  {"occluder_scenes", w.occluder_scenes},
          {"cast", w.cast},           {"linearise", w.linearise},   {"solve", w.solve},
          {"update", w.update},       {"finish", w.finish}};
}

// RunProfile: the run's total, every stage and part, and the categories.
json ProfileJson(const RunProfile& profile) {
  const ClockReading& total = profile.total();
  const double cpu = total.cpu > 0.0 ? total.cpu : 1.0;
  json j;
  j["total"] = {{"wall_seconds", total.wall}, {"cpu_seconds", total.cpu}};
  j["stages_cpu_seconds"] = profile.StagesCpu();
  j["entries"] = json::array();
  for (const ProfileEntry& e : profile.entries()) {
    json entry = {{"level", e.level},          {"cycle", e.cycle},       {"stage", e.stage},
                  {"calls", e.calls},          {"wall_seconds", e.wall}, {"cpu_seconds", e.cpu},
                  {"cpu_share", e.cpu / cpu}};
    if (!e.part.empty()) entry["part"] = e.part;
    if (e.windows.runs > 0) entry["window_thread_cpu_seconds"] = WindowClocksJson(e.windows);
    j["entries"].push_back(entry);
  }
  for (const std::string& name : RunProfile::Categories()) {
    const double seconds = profile.CategoryCpu(name);
    j["categories"][name] = {{"cpu_seconds", seconds}, {"cpu_share", seconds / cpu}};
  }
  return j;
}

// Pixels as a number, null when not finite (JSON has no infinity).
json Pixels(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

json GeometryJson(const GeometryCheck& check) {
  json j = {{"images", check.images.size()},
            {"usable", check.UsableCount()},
            {"region_points", check.region_points},
            {"min_intersection_deg", check.min_intersection_deg},
            {"observations", check.observations},
            {"median_reprojection_px", Pixels(check.median_reprojection_px)},
            {"typical_image_median_px", Pixels(check.typical_image_median_px)},
            {"bad_image_median_px", Pixels(check.bad_image_median_px)}};
  if (check.worst_image >= 0) {
    const ImageGeometry& worst = check.images[check.worst_image];
    j["worst_image"] = {{"image_id", worst.image_id},
                        {"name", worst.name},
                        {"median_reprojection_px", Pixels(worst.median_reprojection_px)}};
  }
  j["dropped"] = json::array();
  for (const ImageGeometry& image : check.images) {
    if (!image.Usable()) j["dropped"].push_back({{"image_id", image.image_id}, {"name", image.name}, {"problems", image.problems}});
  }
  return j;
}

}  // namespace

std::string ReconstructionReport::BriefReport() const {
  std::ostringstream out;
  out << "start height " << start_height << " m; ";
  for (const auto& level : levels) {
    out << "level " << level.level << ": " << level.faces << " faces, " << level.window.iterations.size()
        << " iterations, sigma0 " << level.window.sigma0 << "; ";
  }
  out << seconds_total << " s";
  return out.str();
}

std::string ReconstructionReport::Json() const {
  json j = StartJson(*this);
  if (!geometry.images.empty()) j["geometry_check"] = GeometryJson(geometry);
  long long observations = 0;
  int iterations = 0, cg = 0;
  for (const auto& level : levels) {
    j["levels"].push_back(LevelJson(level));
    observations += level.window.observations;
    for (const auto& window : level.windows) iterations += static_cast<int>(window.iterations.size());
    cg += level.window.cg_iterations_total;
  }
  j["totals"] = {{"levels", levels.size()},
                 {"window_iterations", iterations},
                 {"cg_iterations", cg},
                 {"observations_last_iterations", observations},
                 {"sigma0_finest", levels.empty() ? 0.0 : levels.back().window.sigma0}};
  j["profile"] = ProfileJson(profile);
  return j.dump(2);
}

}  // namespace facets
