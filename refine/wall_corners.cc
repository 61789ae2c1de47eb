#include "refine/wall_corners.h"

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <utility>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "mesh/creases.h"
#include "mesh/local_ops.h"
#include "mesh/principal_axes.h"

namespace facets {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kSteepMaxNz = 0.5;  // a wall: normal more than 60 degrees from +Z

struct Region {
  Eigen::Vector3d centre, normal;
};

PrincipalAxes FitFaces(const TinMesh& mesh, const std::vector<int>& faces) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(3 * faces.size());
  for (int f : faces) {
    for (auto v : mesh.fv_range(mesh.face_handle(f))) points.push_back(ToEigen(mesh.point(v)));
  }
  return FitPrincipalAxes(points);
}

// Planar regions (see the header); the region of each face, -1 for none.
std::vector<Region> GrowRegions(const TinMesh& mesh, const WallCornerOptions& o, std::vector<int>* face_region) {
  const int nf = static_cast<int>(mesh.n_faces());
  const double cos_angle = std::cos(o.region_angle_deg * kDeg);
  const double tol = o.region_tolerance * o.edge_length;
  std::vector<Eigen::Vector3d> fn(nf);
  for (auto f : mesh.faces()) fn[f.idx()] = UnitFaceNormal(mesh, f);
  // Flattest first: the least cosine between a face and its neighbours.
  std::vector<double> flatness(nf, 1.0);
  for (auto f : mesh.faces()) {
    for (auto g : mesh.ff_range(f)) flatness[f.idx()] = std::min(flatness[f.idx()], fn[f.idx()].dot(fn[g.idx()]));
  }
  std::vector<int> order(nf);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return flatness[a] > flatness[b]; });

  face_region->assign(nf, -1);
  std::vector<Region> regions;
  std::vector<bool> seeded(nf, false);
  for (int seed : order) {
    if ((*face_region)[seed] >= 0 || seeded[seed] || flatness[seed] < cos_angle) continue;
    if (fn[seed].squaredNorm() == 0.0) continue;
    seeded[seed] = true;
    const int id = static_cast<int>(regions.size());
    Eigen::Vector3d normal = fn[seed];
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (auto v : mesh.fv_range(mesh.face_handle(seed))) centre += ToEigen(mesh.point(v)) / 3.0;
    std::vector<int> members{seed};
    (*face_region)[seed] = id;
    size_t next_refit = 4;
    for (size_t i = 0; i < members.size(); ++i) {
      const auto f = mesh.face_handle(members[i]);
      for (auto g : mesh.ff_range(f)) {
        const int gi = g.idx();
        if ((*face_region)[gi] >= 0) continue;
        if (fn[gi].dot(fn[f.idx()]) < cos_angle || fn[gi].dot(normal) < cos_angle) continue;
        bool near = true;
        for (auto v : mesh.fv_range(g)) near = near && std::abs((ToEigen(mesh.point(v)) - centre).dot(normal)) <= tol;
        if (!near) continue;
        (*face_region)[gi] = id;
        members.push_back(gi);
      }
      if (members.size() >= next_refit) {
        const PrincipalAxes fit = FitFaces(mesh, members);
        centre = fit.centre;
        normal = fit.Normal().dot(normal) < 0.0 ? Eigen::Vector3d(-fit.Normal()) : fit.Normal();
        next_refit *= 2;
      }
    }
    bool keep = static_cast<int>(members.size()) >= o.min_region_faces;
    if (keep) {
      const PrincipalAxes fit = FitFaces(mesh, members);
      centre = fit.centre;
      normal = fit.Normal().dot(normal) < 0.0 ? Eigen::Vector3d(-fit.Normal()) : fit.Normal();
      keep = std::sqrt(std::max(0.0, fit.eigenvalues(0)) / (3.0 * members.size())) <= tol;
    }
    if (!keep) {
      for (int m : members) (*face_region)[m] = -1;
      continue;
    }
    regions.push_back({centre, normal});
  }
  return regions;
}

// The pairs of steep regions whose vertices come within one edge of each other (they
// share a vertex, or an edge joins them), the most parallel pairs first.
std::vector<std::pair<int, int>> NeighbouringWallPairs(const TinMesh& mesh, const std::vector<int>& face_region,
                                                       const std::vector<Region>& regions,
                                                       const std::vector<bool>& steep) {
  // The steep regions around each vertex, then the pairs an edge (or a vertex) joins.
  std::vector<std::vector<int>> around(mesh.n_vertices());
  for (auto f : mesh.faces()) {
    const int r = face_region[f.idx()];
    if (r < 0 || !steep[r]) continue;
    for (auto v : mesh.fv_range(f)) {
      std::vector<int>& list = around[v.idx()];
      if (std::find(list.begin(), list.end(), r) == list.end()) list.push_back(r);
    }
  }
  std::vector<std::pair<int, int>> pairs;
  auto add_pairs = [&](const std::vector<int>& a, const std::vector<int>& b) {
    for (int i : a) {
      for (int j : b) {
        if (i != j) pairs.emplace_back(std::min(i, j), std::max(i, j));
      }
    }
  };
  for (const std::vector<int>& list : around) add_pairs(list, list);  // a shared vertex
  for (auto e : mesh.edges()) {
    const auto he = mesh.halfedge_handle(e, 0);
    add_pairs(around[mesh.from_vertex_handle(he).idx()], around[mesh.to_vertex_handle(he).idx()]);
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  std::stable_sort(pairs.begin(), pairs.end(), [&](const std::pair<int, int>& a, const std::pair<int, int>& b) {
    return regions[a.first].normal.dot(regions[a.second].normal) >
           regions[b.first].normal.dot(regions[b.second].normal);
  });
  return pairs;
}

int FindRoot(std::vector<int>& root, int r) {
  while (root[r] != r) r = root[r] = root[root[r]];
  return r;
}

// One wall often comes out of GrowRegions in pieces: where its faces crumple near a
// corner, or a lower band leans a few degrees off, the growth stops at a face and starts
// again beyond it, and a piece that shares no edge with the rest keeps its own plane
// (one wall as a region z 1.3..4.9 m and another z 0.4..2.0 m, 9 degrees off). Steep
// regions whose vertices come within one edge of each other are merged when their
// normals lie within region_angle_deg and one plane fits both within region_tolerance,
// the most parallel pairs first (NeighbouringWallPairs); the merged region's plane is
// the fit of all its faces. Returns the number of merges.
int MergeWallPieces(const TinMesh& mesh, const WallCornerOptions& o, std::vector<int>* face_region,
                    std::vector<Region>* regions) {
  const int nr = static_cast<int>(regions->size());
  const double cos_angle = std::cos(o.region_angle_deg * kDeg);
  const double tol = o.region_tolerance * o.edge_length;
  std::vector<bool> steep(nr);
  for (int r = 0; r < nr; ++r) steep[r] = std::abs((*regions)[r].normal.z()) < kSteepMaxNz;
  std::vector<std::vector<int>> faces(nr);
  for (int f = 0; f < static_cast<int>(face_region->size()); ++f) {
    if ((*face_region)[f] >= 0) faces[(*face_region)[f]].push_back(f);
  }
  const std::vector<std::pair<int, int>> pairs = NeighbouringWallPairs(mesh, *face_region, *regions, steep);
  std::vector<int> root(nr);
  std::iota(root.begin(), root.end(), 0);
  int merges = 0;
  for (bool again = true; again;) {
    again = false;
    for (const auto& [i, j] : pairs) {
      const int a = FindRoot(root, i), b = FindRoot(root, j);
      if (a == b) continue;
      if ((*regions)[a].normal.dot((*regions)[b].normal) < cos_angle) continue;
      std::vector<int> both = faces[a];
      both.insert(both.end(), faces[b].begin(), faces[b].end());
      const PrincipalAxes fit = FitFaces(mesh, both);
      if (std::sqrt(std::max(0.0, fit.eigenvalues(0)) / (3.0 * both.size())) > tol) continue;
      const Eigen::Vector3d n = fit.Normal().dot((*regions)[a].normal) < 0.0 ? Eigen::Vector3d(-fit.Normal()) : fit.Normal();
      if (std::abs(n.z()) >= kSteepMaxNz) continue;
      const int keep = std::min(a, b), gone = std::max(a, b);
      root[gone] = keep;
      faces[keep] = std::move(both);
      faces[gone].clear();
      (*regions)[keep] = {fit.centre, n};
      ++merges;
      again = true;
    }
  }
  if (merges == 0) return 0;
  std::vector<int> renumber(nr, -1);
  std::vector<Region> merged;
  for (int r = 0; r < nr; ++r) {
    if (FindRoot(root, r) != r) continue;
    renumber[r] = static_cast<int>(merged.size());
    merged.push_back((*regions)[r]);
  }
  for (int& r : *face_region) {
    if (r >= 0) r = renumber[FindRoot(root, r)];
  }
  *regions = std::move(merged);
  return merges;
}

// The regions seen from the vertices: which are steep (walls), the regions of each
// vertex's faces, whether one of them is a roof or ground, and each region's vertices.
struct RegionMaps {
  std::vector<bool> steep;                        // by region
  std::vector<std::vector<int>> vertex_regions;   // by vertex
  std::vector<bool> on_flat;                      // by vertex
  std::vector<std::vector<int>> region_vertices;  // by region
};

RegionMaps MapRegions(const TinMesh& mesh, const std::vector<Region>& regions, const std::vector<int>& face_region) {
  const int nr = static_cast<int>(regions.size());
  const int nv = static_cast<int>(mesh.n_vertices());
  RegionMaps maps;
  maps.steep.resize(nr);
  for (int r = 0; r < nr; ++r) maps.steep[r] = std::abs(regions[r].normal.z()) < kSteepMaxNz;
  maps.vertex_regions.resize(nv);
  maps.on_flat.assign(nv, false);
  for (auto f : mesh.faces()) {
    const int r = face_region[f.idx()];
    if (r < 0) continue;
    for (auto v : mesh.fv_range(f)) {
      if (!maps.steep[r]) maps.on_flat[v.idx()] = true;
      std::vector<int>& list = maps.vertex_regions[v.idx()];
      if (std::find(list.begin(), list.end(), r) == list.end()) list.push_back(r);
    }
  }
  maps.region_vertices.resize(nr);
  for (int v = 0; v < nv; ++v) {
    for (int r : maps.vertex_regions[v]) maps.region_vertices[r].push_back(v);
  }
  return maps;
}

Eigen::Vector3d VertexPoint(const TinMesh& mesh, int v) { return ToEigen(mesh.point(mesh.vertex_handle(v))); }

// Distance in m of p from the line through q along the unit vector dir.
double OffLine(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& dir) {
  const Eigen::Vector3d d = p - q;
  return (d - d.dot(dir) * dir).norm();
}

// The line where two planes meet: a point on it nearest `near`, and its direction.
void MeetLine(const Region& a, const Region& b, const Eigen::Vector3d& near, Eigen::Vector3d* q,
              Eigen::Vector3d* dir) {
  *dir = a.normal.cross(b.normal).normalized();
  Eigen::Matrix3d m;
  m.row(0) = a.normal.transpose();
  m.row(1) = b.normal.transpose();
  m.row(2) = dir->transpose();
  *q = m.colPivHouseholderQr().solve(Eigen::Vector3d(a.normal.dot(a.centre), b.normal.dot(b.centre), dir->dot(near)));
}

// Feet and eaves: each plane refitted to its region's vertices within local_fit edges
// of the line (q, dir), then the line where the refitted planes meet. False when a
// region has too few vertices there, changes from wall to gentle or back, or the
// planes no longer enclose 45-135 degrees.
bool RefitNearLine(const TinMesh& mesh, const WallCornerOptions& options, const RegionMaps& maps, const int ids[2],
                   Region plane[2], Eigen::Vector3d* q, Eigen::Vector3d* dir) {
  const double h = options.edge_length;
  const double cos_min = std::cos(135.0 * kDeg), cos_max = std::cos(45.0 * kDeg);
  for (int k = 0; k < 2; ++k) {
    std::vector<Eigen::Vector3d> near;
    for (int v : maps.region_vertices[ids[k]]) {
      if (OffLine(VertexPoint(mesh, v), *q, *dir) <= options.local_fit * h) near.push_back(VertexPoint(mesh, v));
    }
    if (static_cast<int>(near.size()) < options.min_region_faces) return false;
    const PrincipalAxes fit = FitPrincipalAxes(near);
    const Eigen::Vector3d n = fit.Normal().dot(plane[k].normal) < 0.0 ? Eigen::Vector3d(-fit.Normal()) : fit.Normal();
    const bool still = maps.steep[ids[k]] == (std::abs(n.z()) < kSteepMaxNz);
    plane[k] = {fit.centre, n};
    if (!still) return false;
  }
  const double c = plane[0].normal.dot(plane[1].normal);
  if (c > cos_max || c < cos_min) return false;
  const Eigen::Vector3d near_line = *q;  // not an alias of the result
  MeetLine(plane[0], plane[1], near_line, q, dir);
  return true;
}

// The common stretch of two regions along the line (q, dir), half an edge short of
// each end, and which side of the first plane the second region lies on: false when a
// region does not come within 1.6 edges of the line or the stretch is under two edges.
bool CommonStretch(const TinMesh& mesh, const RegionMaps& maps, const int ids[2], const Region plane[2], double h,
                   const Eigen::Vector3d& q, const Eigen::Vector3d& dir, WallCorner* corner) {
  // Each region's stretch along the line (its vertices within 2 edges of it), how
  // close it comes, and the mean of those vertices (which side of the other plane
  // the region lies on).
  double lo[2], hi[2], nearest[2];
  Eigen::Vector3d beside[2];
  for (int k = 0; k < 2; ++k) {
    lo[k] = std::numeric_limits<double>::infinity();
    hi[k] = -lo[k];
    nearest[k] = lo[k];
    beside[k].setZero();
    int count = 0;
    for (int v : maps.region_vertices[ids[k]]) {
      const Eigen::Vector3d p = VertexPoint(mesh, v);
      const double d = OffLine(p, q, dir);
      nearest[k] = std::min(nearest[k], d);
      if (d > 2.0 * h) continue;
      const double t = (p - q).dot(dir);
      lo[k] = std::min(lo[k], t);
      hi[k] = std::max(hi[k], t);
      beside[k] += p;
      ++count;
    }
    if (count > 0) beside[k] /= count;
  }
  if (nearest[0] > 1.6 * h || nearest[1] > 1.6 * h) return false;
  const double t0 = std::max(lo[0], lo[1]) + 0.5 * h, t1 = std::min(hi[0], hi[1]) - 0.5 * h;
  if (t1 - t0 < 2.0 * h) return false;
  corner->point = q + 0.5 * (t0 + t1) * dir;
  corner->direction = dir;
  corner->half_length = 0.5 * (t1 - t0);
  for (int k = 0; k < 2; ++k) {
    corner->normal[k] = plane[k].normal;
    corner->centre[k] = plane[k].centre;
  }
  corner->convex = (beside[1] - beside[0]).dot(plane[0].normal) < 0.0;
  return true;
}

// The corner's band: the vertices within `band` edges of its line along its stretch,
// not on the border; for a vertical corner not on a roof or ground region, for a foot
// or an eave on no region but the two.
void CollectBand(const TinMesh& mesh, const WallCornerOptions& options, const RegionMaps& maps, const int ids[2],
                 bool vertical, const Eigen::Vector3d& q, WallCorner* corner) {
  const double h = options.edge_length;
  const Eigen::Vector3d& dir = corner->direction;
  for (auto vh : mesh.vertices()) {
    if (mesh.is_boundary(vh)) continue;
    if (vertical && maps.on_flat[vh.idx()]) continue;
    if (!vertical && std::any_of(maps.vertex_regions[vh.idx()].begin(), maps.vertex_regions[vh.idx()].end(),
                                 [&](int r) { return r != ids[0] && r != ids[1]; }))
      continue;
    const Eigen::Vector3d p = ToEigen(mesh.point(vh));
    const double t = (p - corner->point).dot(dir);
    if (std::abs(t) > corner->half_length || OffLine(p, q, dir) > options.band * h) continue;
    corner->band.push_back(vh.idx());
  }
}

// The corner of regions i and j (i < j), when they make one (see the header).
bool FindCorner(const TinMesh& mesh, const WallCornerOptions& options, const std::vector<Region>& regions,
                const RegionMaps& maps, int i, int j, WallCorner* corner) {
  const std::vector<bool>& steep = maps.steep;
  if (!steep[i] && !steep[j]) return false;
  const bool vertical = steep[i] && steep[j];
  if (vertical ? !options.vertical : !(options.feet || options.eaves)) return false;
  const double cos_min = std::cos(135.0 * kDeg), cos_max = std::cos(45.0 * kDeg);
  const double cos_vertical_min = std::cos((180.0 - options.min_corner_angle_deg) * kDeg);
  const double cos_vertical_max = std::cos(options.min_corner_angle_deg * kDeg);
  // A wall first: its normal gives the corner's orientation.
  const int ids[2] = {steep[i] ? i : j, steep[i] ? j : i};
  Region plane[2] = {regions[ids[0]], regions[ids[1]]};
  const double cos_ab = plane[0].normal.dot(plane[1].normal);
  if (cos_ab > (vertical ? cos_vertical_max : cos_max) || cos_ab < (vertical ? cos_vertical_min : cos_min)) {
    return false;
  }
  Eigen::Vector3d q, dir;
  MeetLine(plane[0], plane[1], 0.5 * (plane[0].centre + plane[1].centre), &q, &dir);
  if (!vertical && !RefitNearLine(mesh, options, maps, ids, plane, &q, &dir)) return false;
  if (!CommonStretch(mesh, maps, ids, plane, options.edge_length, q, dir, corner)) return false;
  corner->kind = vertical ? CreaseKind::kVertical : corner->convex ? CreaseKind::kEave : CreaseKind::kFoot;
  if (corner->kind == CreaseKind::kFoot && !options.feet) return false;
  if (corner->kind == CreaseKind::kEave && !options.eaves) return false;
  CollectBand(mesh, options, maps, ids, vertical, q, corner);
  return !corner->band.empty();
}

}  // namespace

void WallCornerOptions::Check() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("WallCornerOptions: " + what); };
  if (!(edge_length > 0.0)) fail("edge_length must be > 0");
  if (!(region_angle_deg > 0.0 && region_angle_deg < 90.0)) fail("region_angle_deg must lie in (0, 90)");
  if (!(region_tolerance > 0.0)) fail("region_tolerance must be > 0");
  if (min_region_faces < 1) fail("min_region_faces must be >= 1");
  if (!(band > 0.0)) fail("band must be > 0");
  if (!(snap >= 0.0 && snap <= band)) fail("snap must lie in [0, band]");
  if (!(local_fit > 0.0)) fail("local_fit must be > 0");
  if (!(min_corner_angle_deg >= 45.0 && min_corner_angle_deg < 90.0)) fail("min_corner_angle_deg must lie in [45, 90)");
}

const char* CreaseName(CreaseKind kind) {
  switch (kind) {
    case CreaseKind::kFoot: return "foot";
    case CreaseKind::kEave: return "eave";
    default: return "corner";
  }
}

double WallCorner::angle_deg() const {
  return std::acos(std::clamp(normal[0].dot(normal[1]), -1.0, 1.0)) / kDeg;
}

int WallCornerSearch::count(CreaseKind kind) const {
  return static_cast<int>(std::count_if(corners.begin(), corners.end(),
                                        [kind](const WallCorner& c) { return c.kind == kind; }));
}

WallCornerSearch FindWallCorners(const TinMesh& mesh, const WallCornerOptions& options) {
  options.Check();
  WallCornerSearch search;
  std::vector<int> face_region;
  std::vector<Region> regions = GrowRegions(mesh, options, &face_region);
  if (options.merge_wall_pieces) search.merged_walls = MergeWallPieces(mesh, options, &face_region, &regions);
  search.regions = static_cast<int>(regions.size());
  const RegionMaps maps = MapRegions(mesh, regions, face_region);
  for (int r = 0; r < search.regions; ++r) search.wall_regions += maps.steep[r] ? 1 : 0;
  for (int i = 0; i < search.regions; ++i) {
    for (int j = i + 1; j < search.regions; ++j) {
      WallCorner corner;
      if (FindCorner(mesh, options, regions, maps, i, j, &corner)) search.corners.push_back(std::move(corner));
    }
  }
  return search;
}

namespace {

// The point of the corner's line nearest p.
Eigen::Vector3d OntoCornerLine(const WallCorner& corner, const Eigen::Vector3d& p) {
  return corner.point + (p - corner.point).dot(corner.direction) * corner.direction;
}

// Each band vertex onto the nearer wall's plane (onto the line within snap edges of it,
// or when it would end beyond the other wall). Returns the vertices moved with where
// they were.
std::vector<std::pair<int, Eigen::Vector3d>> MoveBandOntoWalls(TinMesh* mesh, const WallCorner& corner,
                                                               const WallCornerOptions& options) {
  const double snap = options.snap * options.edge_length;
  std::vector<std::pair<int, Eigen::Vector3d>> moved;  // vertex, where it was
  for (int v : corner.band) {
    const auto vh = mesh->vertex_handle(v);
    const Eigen::Vector3d p = ToEigen(mesh->point(vh));
    const double s[2] = {(p - corner.centre[0]).dot(corner.normal[0]), (p - corner.centre[1]).dot(corner.normal[1])};
    // A convex corner's solid is inside both planes: the surface point nearest is on the
    // plane with the larger signed distance; a re-entrant corner's is inside either.
    const int k = corner.convex == (s[0] >= s[1]) ? 0 : 1;
    Eigen::Vector3d target = p - s[k] * corner.normal[k];
    const double other = (target - corner.centre[1 - k]).dot(corner.normal[1 - k]);
    const bool beyond = corner.convex ? other > 0.0 : other < 0.0;
    const Eigen::Vector3d on_line = OntoCornerLine(corner, target);
    if (beyond || (target - on_line).norm() < snap) target = on_line;
    if ((target - p).norm() < 1e-6 * options.edge_length) continue;  // on its wall already
    mesh->set_point(vh, ToOpenMesh(target));
    moved.emplace_back(v, p);
  }
  return moved;
}

// A face that lost its area (least height under 5 % of its longest edge) or turned its
// back on the walls (against `outward`, their mean normal, or its neighbours).
bool TurnedOrFlat(const TinMesh& mesh, TinMesh::FaceHandle f, const Eigen::Vector3d& outward) {
  std::array<Eigen::Vector3d, 3> p;
  int i = 0;
  for (auto v : mesh.fv_range(f)) p[i++] = ToEigen(mesh.point(v));
  const Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]);
  const double longest = std::max({(p[1] - p[0]).norm(), (p[2] - p[1]).norm(), (p[0] - p[2]).norm()});
  if (NoArea(n.norm(), longest, 0.05)) return true;
  if (n.dot(outward) < 0.0) return true;
  Eigen::Vector3d around = Eigen::Vector3d::Zero();
  for (auto g : mesh.ff_range(f)) around += UnitFaceNormal(mesh, g);
  return n.dot(around) < 0.0;
}

// Two band vertices can swap sides, or three end on the line: a face around them that
// turned its back on the walls or lost its area gets the corner that moved most back
// where it was, until none is left. Returns how many went back (restored[k] set).
int PutBackWhereFacesTurn(TinMesh* mesh, const WallCorner& corner,
                          const std::vector<std::pair<int, Eigen::Vector3d>>& moved, std::vector<char>* restored) {
  const Eigen::Vector3d outward = corner.normal[0] + corner.normal[1];
  std::unordered_map<int, size_t> slot;  // vertex -> its entry in moved
  for (size_t k = 0; k < moved.size(); ++k) slot[moved[k].first] = k;
  int left_off = 0;
  for (size_t round = 0; round < moved.size(); ++round) {
    std::vector<char> restore(moved.size(), 0);
    bool any = false;
    for (size_t k = 0; k < moved.size(); ++k) {
      if ((*restored)[k]) continue;
      for (auto f : mesh->vf_range(mesh->vertex_handle(moved[k].first))) {
        if (!TurnedOrFlat(*mesh, f, outward)) continue;
        // The corner of this face that moved most (among those still moved).
        size_t worst = k;
        double most = -1.0;
        for (auto v : mesh->fv_range(f)) {
          const auto it = slot.find(v.idx());
          if (it == slot.end() || (*restored)[it->second]) continue;
          const double d = (ToEigen(mesh->point(v)) - moved[it->second].second).norm();
          if (d > most) most = d, worst = it->second;
        }
        restore[worst] = 1;
        any = true;
      }
    }
    if (!any) break;
    for (size_t k = 0; k < moved.size(); ++k) {
      if (!restore[k]) continue;
      mesh->set_point(mesh->vertex_handle(moved[k].first), ToOpenMesh(moved[k].second));
      (*restored)[k] = 1;
      ++left_off;
    }
  }
  return left_off;
}

}  // namespace

CornerLaying LayCornerOntoWalls(TinMesh* mesh, const WallCorner& corner, const WallCornerOptions& options) {
  options.Check();
  CornerLaying laying;
  const std::vector<std::pair<int, Eigen::Vector3d>> moved = MoveBandOntoWalls(mesh, corner, options);
  std::vector<char> restored(moved.size(), 0);
  laying.left_off = PutBackWhereFacesTurn(mesh, corner, moved, &restored);
  for (size_t k = 0; k < moved.size(); ++k) {
    if (restored[k]) continue;
    ++laying.moved;
    const Eigen::Vector3d p = ToEigen(mesh->point(mesh->vertex_handle(moved[k].first)));
    laying.max_move = std::max(laying.max_move, (p - moved[k].second).norm());
    if ((p - OntoCornerLine(corner, p)).norm() < 1e-9) ++laying.on_line;
  }
  return laying;
}

}  // namespace facets
