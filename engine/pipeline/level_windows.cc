#include "engine/pipeline/level_windows.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>

#include "engine/pipeline/window_occluders.h"
#include "mesh/creases.h"
#include "visibility/embree_scene.h"
#include "visibility/image_selection.h"

namespace facets {
namespace {

struct WindowResult {
  WindowReport report;
  bool observed = false;
  std::string error;
  std::vector<int> global_face;
  std::vector<Eigen::Vector3i> triangles;  // of the window's tessellation
  std::vector<double> grey;
  int channels = 1;
};

Eigen::AlignedBox3d VertexBox(const TinMesh& mesh) {
  Eigen::AlignedBox3d box;
  for (auto vh : mesh.vertices()) box.extend(ToEigen(mesh.point(vh)));
  return box;
}

// How far a window's faces may move before its occluders are selected again (object
// units): a twentieth of its box's diagonal. At level 1 of block_oblique one window run
// in ten selects again; a wider slack selects more occluders for every run, a narrower
// one selects more often (docs/BENCHMARKS.md "Occluders selected by depth").
double OccluderSlack(const TinMesh& mesh) { return 0.05 * VertexBox(mesh).diagonal().norm(); }

// The window's surface grown by a quarter of its size: the surface moves during the
// adjustment, and the images (regions) must cover where it goes.
Eigen::AlignedBox3d GrownBox(const TinMesh& mesh) {
  Eigen::AlignedBox3d box = VertexBox(mesh);
  const Eigen::Vector3d grow = Eigen::Vector3d::Constant(0.25 * box.diagonal().norm());
  box.extend(box.min() - grow);
  box.extend(box.max() + grow);
  return box;
}

// The window run, and a second run when the first one sharpened new creases (the
// adjustment keeps one crease set per run).
WindowReport RunWithCreasePass(TinMesh* mesh, const std::vector<LevelImage>& images,
                               const AdjustmentOptions& options, const std::vector<bool>& fixed,
                               const std::vector<bool>& judged,
                               WindowOccluders* occluders, bool second_pass, WindowResult* result) {
  auto run = [&]() {
    auto adjustment = std::make_unique<WindowAdjustment>(mesh, images, options);
    adjustment->SetFixedVertices(fixed);
    adjustment->SetBreakOffVertices(judged);
    if (occluders) {
      adjustment->SetOccluderSource(
          [occluders](const std::vector<Eigen::AlignedBox3d>& boxes) { return occluders->For(boxes); });
    }
    WindowReport report = adjustment->Run();
    result->triangles = adjustment->tessellation().triangles;
    result->grey = adjustment->grey();
    result->channels = adjustment->channels();
    return report;
  };
  WindowReport first = run();
  if (!second_pass) return first;
  const std::vector<bool> creases = DetectCreaseEdges(*mesh, options.crease_angle_deg, options.rounded_ridges);
  const int found = static_cast<int>(std::count(creases.begin(), creases.end(), true));
  if (found <= first.crease_edges) return first;
  // The second run is kept only if it fits better: a crease set that frees crumpled
  // vertices of their regularisation (a wall's folds) fits worse and is dropped.
  std::vector<TinMesh::Point> first_points;
  for (auto vh : mesh->vertices()) first_points.push_back(mesh->point(vh));
  const std::vector<Eigen::Vector3i> first_triangles = result->triangles;
  const std::vector<double> first_grey = result->grey;
  WindowReport second = run();
  if (second.sigma0 > first.sigma0) {
    for (auto vh : mesh->vertices()) mesh->set_point(vh, first_points[vh.idx()]);
    UpdateVertexNormals(mesh);
    result->triangles = first_triangles;
    result->grey = first_grey;
    first.crease_passes_dropped = 1;
    first.crease_pass_iterations_dropped = static_cast<int>(second.iterations.size());
    return first;
  }
  const int first_iterations = static_cast<int>(first.iterations.size());
  for (auto& it : second.iterations) it.iteration += first_iterations;
  second.iterations.insert(second.iterations.begin(), first.iterations.begin(),
                           first.iterations.end());
  second.cg_iterations_total += first.cg_iterations_total;
  return second;
}

Tessellation TessellateWithCreases(const TinMesh& mesh, const AdjustmentOptions& options) {
  const CornerNormals corners =
      ComputeCornerNormals(mesh, DetectCreaseEdges(mesh, options.crease_angle_deg, options.rounded_ridges));
  return Tessellate(mesh, BuildPatches(mesh, corners), corners);
}

// The per-vertex results of a window's last sweep re-indexed to its owned vertices
// (MeshWindow order); a window without observations gives sigma 0, no views.
void KeepOwnedVertexResults(const WindowMesh& wm, WindowResult* result) {
  WindowReport& r = result->report;
  std::vector<double> sigma;
  std::vector<int> views;
  std::vector<uint8_t> flags;
  for (int local : wm.owned_local) {
    sigma.push_back(result->observed ? r.vertex_sigma[local] : 0.0);
    views.push_back(result->observed ? r.vertex_views[local] : 0);
    flags.push_back(result->observed ? r.vertex_flags[local] : uint8_t{kVertexFewViews});
  }
  r.vertex_sigma = std::move(sigma);
  r.vertex_views = std::move(views);
  r.vertex_flags = std::move(flags);
}

// What the windows of one level run share.
struct LevelRun {
  TinMesh* mesh;
  const WindowImages& images;
  const AdjustmentOptions& adjustment;
  const LevelWindowOptions& options;
  const std::vector<MeshWindow>& windows;
  bool many;  // surface outside the windows: occluders, margins held
  int sweeps;
  int free_margin_sweeps;
  std::vector<WindowResult>& results;
  std::mutex& say_mutex;  // guards `done` and the progress callback
  int& done;              // windows finished, over all sweeps
  const std::function<void(const std::string&)>& progress;
};

// Runs the adjustment of one window of a sweep into result->report (result->error when
// it fails).
void RunWindow(const LevelRun& run, const std::vector<LevelImage>& seeing, int sweep, WindowOccluders* occluders,
               WindowMesh* wm, WindowResult* result) {
  try {
    if (seeing.empty()) throw std::runtime_error("no image sees the window");
    const std::vector<bool> fixed =
        sweep < run.free_margin_sweeps ? std::vector<bool>(wm->fixed.size(), false) : wm->fixed;
    std::vector<bool> judged(wm->fixed.size(), !run.many);
    for (int local : wm->owned_local) judged[local] = true;
    // Per-vertex sigma and the residuals' correlation are taken from the last sweep
    // only: earlier sweeps skip the precision (one solve per geometry unknown).
    AdjustmentOptions sweep_options = run.adjustment;
    if (sweep + 1 < run.sweeps) {
      sweep_options.compute_precision = false;
      sweep_options.residual_correlation = false;
    }
    result->report = RunWithCreasePass(&wm->mesh, seeing, sweep_options, fixed, judged, occluders,
                                       run.options.crease_second_pass, result);
    result->observed = true;
  } catch (const std::runtime_error& e) {
    result->error = e.what();
  }
}

// The progress line of one finished window.
std::string WindowLine(const LevelRun& run, int finished, int w, int sweep, const WindowResult& result) {
  std::string line = "  window " + std::to_string(finished) + "/" +
                     std::to_string(run.windows.size() * run.sweeps) + " (#" +
                     std::to_string(w + 1) + ")" +
                     (run.sweeps > 1 ? ", sweep " + std::to_string(sweep + 1) : "") +
                     ": " + std::to_string(run.windows[w].core_faces.size()) + " core faces, ";
  if (result.observed) {
    line += std::to_string(result.report.iterations.size()) + " iterations, sigma0 " +
            std::to_string(result.report.sigma0) + ", " +
            std::to_string(result.report.observations) + " observations" +
            (result.report.converged ? "" : result.report.stalled ? " (stalled)" : " (not converged)");
  } else {
    line += "not adjusted: " + result.error;
  }
  return line;
}

// One window of one sweep: extracted, adjusted, its core's vertices written back into
// the level's mesh. `snapshot` and `surface` (its face boxes): the surface before the
// window's group, for the occluders.
void AdjustWindow(const LevelRun& run, int w, int sweep, const Tessellation& snapshot, const FaceBoxIndex& surface) {
  TinMesh* mesh = run.mesh;
  WindowMesh wm = ExtractWindowMesh(*mesh, run.windows[w]);
  WindowResult& result = run.results[w];
  result = WindowResult{};
  result.global_face = wm.global_face;
  ImageStorage storage;  // the window's image regions, freed with the window
  const Eigen::AlignedBox3d grown = GrownBox(wm.mesh);
  const std::vector<LevelImage> seeing = run.images(grown, &storage);
  // The occluders, selected for the window's surface within OccluderSlack of where it
  // starts, for every run of the window (a second run when the first sharpened new creases).
  std::unique_ptr<WindowOccluders> occluders;
  if (run.many && run.options.occluders) {
    occluders = std::make_unique<WindowOccluders>(run.windows[w], snapshot, surface, seeing, OccluderSlack(wm.mesh));
  }
  RunWindow(run, seeing, sweep, occluders.get(), &wm, &result);
  // Only the core's vertices go back into the level's mesh.
  for (int local : wm.owned_local) {
    const auto lh = wm.mesh.vertex_handle(local);
    const auto gh = mesh->vertex_handle(wm.global_vertex[local]);
    mesh->set_point(gh, wm.mesh.point(lh));
    mesh->set_normal(gh, wm.mesh.normal(lh));
  }
  int finished = 0;
  {
    std::lock_guard<std::mutex> lock(run.say_mutex);
    finished = ++run.done;
  }
  const std::string line = WindowLine(run, finished, w, sweep, result);
  {
    std::lock_guard<std::mutex> lock(run.say_mutex);
    if (run.progress) run.progress(line);
  }
  if (sweep + 1 == run.sweeps) KeepOwnedVertexResults(wm, &result);
}

// Adds one observed window's counts to the level's summary; *pooled: sum of sigma0^2 r.
void AddToSummary(const WindowReport& r, WindowReport* s, double* pooled) {
  s->converged = s->converged && r.converged;
  s->observations += r.observations;
  s->pseudo_observations += r.pseudo_observations;
  s->background += r.background;
  s->rejected += r.rejected;
  s->downweighted += r.downweighted;
  s->silhouette += r.silhouette;
  s->silhouette_outside += r.silhouette_outside;
  s->unknowns += r.unknowns;
  s->redundancy += r.redundancy;
  s->cg_iterations_total += r.cg_iterations_total;
  s->crease_edges += r.crease_edges;
  s->crease_passes_dropped += r.crease_passes_dropped;
  s->crease_pass_iterations_dropped += r.crease_pass_iterations_dropped;
  s->seconds_precision += r.seconds_precision;
  s->precision_computed = s->precision_computed && r.precision_computed;
  *pooled += r.sigma0 * r.sigma0 * static_cast<double>(r.redundancy);
  // Correlation and variance factor: means weighted by the redundancy.
  s->residual_rho_x += r.residual_rho_x * static_cast<double>(r.redundancy);
  s->residual_rho_y += r.residual_rho_y * static_cast<double>(r.redundancy);
  s->variance_factor += r.variance_factor * static_cast<double>(r.redundancy);
  if (r.iterations.size() > s->iterations.size()) s->iterations = r.iterations;
}

// Each core face's part of its window's fit (FaceFit); a local run starts from the
// previous adjustment's parts.
void ShareFitAmongCoreFaces(const std::vector<MeshWindow>& windows, const std::vector<WindowResult>& results,
                            const LocalScope* local, int num_faces, FaceFit* fit) {
  if (local) *fit = local->previous->face_fit;
  fit->vpv.resize(num_faces, 0.0);
  fit->redundancy.resize(num_faces, 0.0);
  fit->observations.resize(num_faces, 0.0);
  for (size_t w = 0; w < windows.size(); ++w) {
    const WindowReport& r = results[w].report;
    const bool observed = results[w].observed;
    const double faces = static_cast<double>(std::max<size_t>(1, windows[w].core_faces.size()));
    const double redundancy = observed ? static_cast<double>(r.redundancy) : 0.0;
    for (int f : windows[w].core_faces) {
      fit->vpv[f] = observed ? r.sigma0 * r.sigma0 * redundancy / faces : 0.0;
      fit->redundancy[f] = redundancy / faces;
      fit->observations[f] = observed ? static_cast<double>(r.observations) / faces : 0.0;
    }
  }
}

// The level's summary and per-vertex values from its windows (LevelAdjustment::summary).
void Summarise(const std::vector<MeshWindow>& windows, const std::vector<WindowResult>& results,
               const LocalScope* local, int num_vertices, LevelAdjustment* level) {
  WindowReport& s = level->summary;
  s.converged = true;
  if (local) {
    s.vertex_sigma = local->previous->summary.vertex_sigma;
    s.vertex_views = local->previous->summary.vertex_views;
    s.vertex_flags = local->previous->summary.vertex_flags;
  } else {
    s.vertex_sigma.assign(num_vertices, 0.0);
    s.vertex_views.assign(num_vertices, 0);
    s.vertex_flags.assign(num_vertices, kVertexFewViews);
  }
  s.precision_computed = true;
  s.variance_factor = 0.0;  // pooled below
  double pooled = 0.0;
  bool any = false;
  for (size_t w = 0; w < windows.size(); ++w) {
    const WindowResult& result = results[w];
    const WindowReport& r = result.report;
    for (size_t i = 0; i < windows[w].owned_vertices.size(); ++i) {
      const int v = windows[w].owned_vertices[i];
      s.vertex_sigma[v] = r.vertex_sigma[i];
      s.vertex_views[v] = r.vertex_views[i];
      s.vertex_flags[v] = static_cast<uint8_t>(r.vertex_flags[i] & ~kVertexFixed);
    }
    if (!result.observed) {
      s.converged = false;
      level->windows.push_back(r);
      continue;
    }
    any = true;
    AddToSummary(r, &s, &pooled);
    level->windows.push_back(r);
  }
  if (!any) {
    throw std::runtime_error("no window of the level has any observation (" +
                             results.front().error + ")");
  }
  s.sigma0 = s.redundancy > 0 ? std::sqrt(pooled / static_cast<double>(s.redundancy)) : 0.0;
  if (s.redundancy > 0) {
    s.residual_rho_x /= static_cast<double>(s.redundancy);
    s.residual_rho_y /= static_cast<double>(s.redundancy);
    s.variance_factor /= static_cast<double>(s.redundancy);
  } else {
    s.variance_factor = 1.0;
  }
  s.radiometry = windows.size() == 1 && !local ? results.front().report.radiometry
                                     : std::vector<std::vector<std::array<double, 2>>>{};
}

// Grey values of the level's tessellation, each face's from the window whose core holds
// it (face_window: that window per face, -1 outside every core).
void CopyWindowGrey(const std::vector<WindowResult>& results, const std::vector<int>& face_window, int channels,
                    LevelAdjustment* level) {
  for (size_t w = 0; w < results.size(); ++w) {
    const WindowResult& result = results[w];
    if (!result.observed) continue;
    for (size_t lf = 0; lf < result.global_face.size(); ++lf) {
      const int f = result.global_face[lf];
      if (face_window[f] != static_cast<int>(w)) continue;
      for (int k = 0; k < kSubTrianglesPerFace; ++k) {
        const Eigen::Vector3i& to = level->tessellation.triangles[f * kSubTrianglesPerFace + k];
        const Eigen::Vector3i& from = result.triangles[lf * kSubTrianglesPerFace + k];
        for (int corner = 0; corner < 3; ++corner) {
          for (int c = 0; c < channels; ++c) {
            level->grey[static_cast<size_t>(to[corner]) * channels + c] =
                result.grey[static_cast<size_t>(from[corner]) * channels + c];
          }
        }
      }
    }
  }
}

// Faces outside a local run's cores: the grey values of the previous adjustment
// (same faces, same sub-triangles) where no local window set them. A level split since
// has more faces than the previous adjustment; its new faces are in the cores.
void CopyPreviousGrey(const LevelAdjustment* previous, const std::vector<int>& face_window, int channels,
                      LevelAdjustment* level) {
  if (!previous || previous->tessellation.triangles.size() > level->tessellation.triangles.size() ||
      previous->grey.empty()) {
    return;
  }
  const int previous_channels =
      static_cast<int>(previous->grey.size() / std::max<size_t>(1, previous->tessellation.points.size()));
  const size_t previous_faces = previous->tessellation.triangles.size() / kSubTrianglesPerFace;
  for (size_t f = 0; f < std::min(face_window.size(), previous_faces) && previous_channels == channels; ++f) {
    if (face_window[f] >= 0) continue;
    for (int k = 0; k < kSubTrianglesPerFace; ++k) {
      const Eigen::Vector3i& to = level->tessellation.triangles[f * kSubTrianglesPerFace + k];
      const Eigen::Vector3i& from = previous->tessellation.triangles[f * kSubTrianglesPerFace + k];
      for (int corner = 0; corner < 3; ++corner) {
        for (int c = 0; c < channels; ++c) {
          double& grey = level->grey[static_cast<size_t>(to[corner]) * channels + c];
          if (!std::isfinite(grey)) grey = previous->grey[static_cast<size_t>(from[corner]) * channels + c];
        }
      }
    }
  }
}

// LevelAdjustment::tessellation and grey of the final surface (keep_grey).
void GatherLevelGrey(const TinMesh& mesh, const AdjustmentOptions& adjustment,
                     const std::vector<WindowResult>& results, const std::vector<int>& face_window,
                     const LocalScope* local, LevelAdjustment* level) {
  level->tessellation = TessellateWithCreases(mesh, adjustment);
  const int channels = results.front().channels;
  level->grey.assign(level->tessellation.points.size() * channels,
                     std::numeric_limits<double>::quiet_NaN());
  CopyWindowGrey(results, face_window, channels, level);
  CopyPreviousGrey(local ? local->previous : nullptr, face_window, channels, level);
  // Nodes of windows without observations: the mean grey value.
  double sum = 0.0;
  long long count = 0;
  for (double g : level->grey) {
    if (std::isfinite(g)) sum += g, ++count;
  }
  for (double& g : level->grey) {
    if (!std::isfinite(g)) g = count > 0 ? sum / count : 0.0;
  }
}

}  // namespace

double FaceFit::Sigma0(const std::vector<int>* faces) const {
  double vpv_sum = 0.0, redundancy_sum = 0.0;
  auto add = [&](size_t f) {
    vpv_sum += vpv[f];
    redundancy_sum += redundancy[f];
  };
  if (faces) {
    for (int f : *faces) {
      if (f >= 0 && static_cast<size_t>(f) < vpv.size()) add(f);
    }
  } else {
    for (size_t f = 0; f < vpv.size(); ++f) add(f);
  }
  return redundancy_sum > 0.0 && vpv_sum > 0.0 ? std::sqrt(vpv_sum / redundancy_sum) : 0.0;
}

double FaceFit::TotalRedundancy() const { return std::accumulate(redundancy.begin(), redundancy.end(), 0.0); }

double FaceFit::TotalObservations() const { return std::accumulate(observations.begin(), observations.end(), 0.0); }

void LevelWindowOptions::Check() const {
  partition.Check();
  if (sweeps < 1) throw std::invalid_argument("windows: sweeps must be >= 1");
  if (free_margin_sweeps < 0) throw std::invalid_argument("windows: free_margin_sweeps must be >= 0");
}

LevelAdjustment AdjustLevelInWindows(TinMesh* mesh, const std::vector<LevelImage>& images,
                                     const AdjustmentOptions& adjustment,
                                     const LevelWindowOptions& options, bool keep_grey,
                                     const std::function<void(const std::string&)>& progress,
                                     const LocalScope* local) {
  const WindowImages seeing = [&](const Eigen::AlignedBox3d& box, ImageStorage*) {
    std::vector<LevelImage> list;
    for (const LevelImage& image : images) {
      if (ProjectBox(box, *image.camera, image.cam_from_world)) list.push_back(image);
    }
    return list;
  };
  return AdjustLevelInWindows(mesh, seeing, adjustment, options, keep_grey, progress, local);
}

LevelAdjustment AdjustLevelInWindows(TinMesh* mesh, const WindowImages& images,
                                     const AdjustmentOptions& adjustment,
                                     const LevelWindowOptions& options, bool keep_grey,
                                     const std::function<void(const std::string&)>& progress,
                                     const LocalScope* local) {
  options.Check();
  if (local && (!local->previous || local->previous->summary.vertex_sigma.size() != mesh->n_vertices())) {
    throw std::invalid_argument("local re-adjustment: needs the level's previous adjustment of the same mesh");
  }
  const auto start = std::chrono::steady_clock::now();
  LevelAdjustment level;
  const std::vector<MeshWindow> windows = local ? local->windows : PartitionIntoWindows(*mesh, options.partition);
  if (windows.empty()) throw std::runtime_error("no window to adjust");
  const std::vector<std::vector<int>> groups = IndependentWindowGroups(*mesh, windows);
  level.groups = static_cast<int>(groups.size());
  for (const auto& w : windows) level.window_core_faces.push_back(static_cast<int>(w.core_faces.size()));
  // A local run has surface outside its windows: occluders and fixed margins as with many.
  const bool many = windows.size() > 1 || local;
  std::vector<int> face_window(mesh->n_faces(), -1);
  for (size_t w = 0; w < windows.size(); ++w) {
    for (int f : windows[w].core_faces) face_window[f] = static_cast<int>(w);
  }

  std::vector<WindowResult> results(windows.size());
  std::mutex say_mutex;
  int done = 0;
  // One window holds every vertex: nothing to sweep over. A local run's neighbours are
  // adjusted already: margins held from the first sweep on.
  const LevelRun run{mesh, images, adjustment, options, windows, many, many ? options.sweeps : 1,
                     local ? 0 : options.free_margin_sweeps, results, say_mutex, done, progress};
  for (int sweep = 0; sweep < run.sweeps; ++sweep) {
    for (const std::vector<int>& group : groups) {
      // The surface as it stands before this group, for the occluders: the windows of a
      // group change disjoint parts and must not read each other's half-moved state.
      Tessellation snapshot;
      if (many && options.occluders) snapshot = TessellateWithCreases(*mesh, adjustment);
      const FaceBoxIndex surface(FaceBoxes(snapshot));
      tbb::parallel_for(size_t{0}, group.size(), [&](size_t g) {
        AdjustWindow(run, group[g], sweep, snapshot, surface);
      });
    }
  }
  UpdateVertexNormals(mesh);

  Summarise(windows, results, local, static_cast<int>(mesh->n_vertices()), &level);
  ShareFitAmongCoreFaces(windows, results, local, static_cast<int>(mesh->n_faces()), &level.face_fit);
  if (keep_grey) GatherLevelGrey(*mesh, adjustment, results, face_window, local, &level);
  level.summary.seconds_total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return level;
}

}  // namespace facets
