#include "apps/creases_command.h"

#include <algorithm>
#include <iomanip>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <utility>

#include "engine/pipeline/products.h"
#include "io/ply_io.h"
#include "mesh/closed_surface.h"
#include "mesh/surface_validity.h"
#include "mesh/tin.h"

namespace facets {

CreasesSummary RunCreases(const CreasesArgs& args, std::ostream& log) {
  if (!(args.corners.edge_length > 0.0)) {
    throw std::invalid_argument("--edge must be > 0 (the level's target edge length, m)");
  }
  if (args.untangle_rounds < 0) throw std::invalid_argument("--untangle-rounds must be >= 0");
  const WallCornerOptions& options = args.corners;
  if (!options.vertical && !options.feet && !options.eaves) {
    throw std::invalid_argument("nothing to lay: all three kinds left out");
  }
  options.Check();
  // Facets' own readers (io/ply_io.h): they check the file before trusting its counts.
  const MeshData tin = ReadMesh(args.tin);
  TinMesh mesh = TinFromTriangles(tin.vertices, tin.faces, args.tin);
  WallCornerSearch search = FindWallCorners(mesh, options);
  // The engine's order: vertical corners first (their bands end short of feet and eaves).
  std::stable_sort(search.corners.begin(), search.corners.end(),
                   [](const WallCorner& a, const WallCorner& b) { return a.kind < b.kind; });
  log << args.tin << ": " << mesh.n_vertices() << " vertices, " << mesh.n_faces() << " faces; " << search.regions
      << " planar regions (" << search.wall_regions << " walls, "
      << search.merged_walls << " wall pieces merged), " << search.count(CreaseKind::kVertical)
      << " vertical corners, " << search.count(CreaseKind::kFoot) << " feet, " << search.count(CreaseKind::kEave)
      << " eaves\n";
  CreasesSummary summary;
  summary.found = static_cast<int>(search.corners.size());
  int crossing = summary.crossing_before = CountSelfIntersections(mesh);
  int folded = summary.folded_before = CountFoldedFaces(mesh);
  for (const WallCorner& corner : search.corners) {
    TinMesh before = mesh;
    const CornerLaying laid = LayCornerOntoWalls(&mesh, corner, options);
    if (laid.moved == 0) continue;
    UpdateVertexNormals(&mesh);
    int crossing_now = CountSelfIntersections(mesh), folded_now = CountFoldedFaces(mesh);
    if ((crossing_now > crossing || folded_now > folded) && args.untangle_rounds > 0) {
      crossing_now = UntangleSelfIntersections(&mesh, args.untangle_rounds).pairs_after;
      UpdateVertexNormals(&mesh);
      folded_now = CountFoldedFaces(mesh);
    }
    const bool worse = crossing_now > crossing || folded_now > folded;
    log << std::fixed << std::setprecision(3) << CreaseName(corner.kind) << " at (" << corner.point.x() << ", "
        << corner.point.y() << ", " << corner.point.z() << "), planes " << std::setprecision(1) << corner.angle_deg()
        << " deg apart, " << std::setprecision(3) << 2.0 * corner.half_length << " m long, " << laid.moved
        << " vertices (" << laid.on_line << " onto the line), max move " << laid.max_move << " m"
        << (worse ? ": " + std::to_string(crossing_now - crossing) + " crossing pairs and " +
                        std::to_string(folded_now - folded) + " folded faces, left"
                  : std::string(", laid"))
        << "\n";
    if (worse) {
      mesh = std::move(before);
      ++summary.left;
    } else {
      crossing = crossing_now;
      folded = folded_now;
      ++summary.laid;
    }
  }
  summary.crossing_after = crossing;
  summary.folded_after = folded;
  WritePly(args.out, TinGeometryData(mesh));  // to a temporary name, renamed at the end
  log << "summary: " << summary.found << " creases found, " << summary.laid << " laid, " << summary.left
      << " left; crossing triangle pairs " << summary.crossing_before << " -> " << summary.crossing_after
      << ", folded faces " << summary.folded_before << " -> " << summary.folded_after << "; written " << args.out
      << "\n";
  return summary;
}

void AddCreasesCommand(CLI::App& app) {
  auto args = std::make_shared<CreasesArgs>();
  CLI::App* sub = app.add_subcommand(
      "creases",
      "lay a TIN's vertical building corners, walls' feet and eaves onto their planes without images (the wall "
      "crease step of `facets reconstruct`; give it levels/level_0_creases.ply of a --keep-levels run)");
  sub->add_option("tin", args->tin, "TIN (PLY, OBJ)")->required();
  sub->add_option("--out", args->out, "output TIN (PLY)")->required();
  WallCornerOptions& corners = args->corners;
  sub->add_option("--edge", corners.edge_length,
                  "the level's target edge length in m (4 x facet pixels x ground pixel)")
      ->required();
  sub->add_flag("!--no-corners", corners.vertical, "leave vertical corners out");
  sub->add_flag("!--no-feet", corners.feet, "leave walls' feet out");
  sub->add_flag("!--no-eaves", corners.eaves, "leave eaves out");
  sub->add_option("--min-angle", corners.min_corner_angle_deg,
                  "least angle in degrees between two walls' normals for a vertical corner (as "
                  "reconstruct's --wall-corner-min-angle)")
      ->capture_default_str();
  sub->add_flag("!--no-merge", corners.merge_wall_pieces, "keep the planar wall pieces apart (as --no-wall-merge)");
  sub->add_option("--untangle-rounds", args->untangle_rounds, "untangling rounds before a crease is left")
      ->capture_default_str();
  sub->callback([args] {
    try {
      RunCreases(*args, std::cout);
    } catch (const std::exception& e) {
      std::cerr << "facets creases: error: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace facets
