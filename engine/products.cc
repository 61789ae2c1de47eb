#include "engine/products.h"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/gltf_io.h"
#include "io/raster_io.h"
#include "io/vrml_io.h"
#include "visibility/surface_scene.h"
#include "visibility/top_view.h"

namespace facets {
namespace {

std::vector<std::array<int, 3>> FaceVertices(const TinMesh& mesh) {
  std::vector<std::array<int, 3>> out(mesh.n_faces());
  for (auto fh : mesh.faces()) {
    int k = 0;
    for (auto vh : mesh.fv_range(fh)) out[fh.idx()][k++] = vh.idx();
  }
  return out;
}

}  // namespace

void ProductOptions::Check() const {
  if (!(raster_pixel >= 0.0)) throw std::invalid_argument("product options: raster_pixel must be >= 0");
}

std::vector<double> NodeSigma(const Reconstruction& r) {
  const auto faces = FaceVertices(r.mesh);
  const Tessellation& tess = r.tessellation;
  std::vector<double> sigma(tess.points.size(), 0.0);
  for (size_t p = 0; p < tess.points.size(); ++p) {
    const auto& v = faces[tess.point_face[p]];
    for (int i = 0; i < 3; ++i) sigma[p] += tess.point_barycentric[p][i] * r.vertex_sigma[v[i]];
  }
  return sigma;
}

std::vector<int> NodeViews(const Reconstruction& r) {
  const auto faces = FaceVertices(r.mesh);
  const Tessellation& tess = r.tessellation;
  std::vector<int> views(tess.points.size(), 0);
  for (size_t p = 0; p < tess.points.size(); ++p) {
    const auto& v = faces[tess.point_face[p]];
    views[p] = std::min({r.vertex_views[v[0]], r.vertex_views[v[1]], r.vertex_views[v[2]]});
  }
  return views;
}

namespace {

// Node values shared by the surface products, computed once.
struct NodeAttributes {
  std::vector<double> sigma;
  std::vector<int> views;
};

ExportSurface MakeExportSurface(const Reconstruction& r, const ImageBlock& block,
                                const NodeAttributes& nodes) {
  ExportSurface surface;
  surface.vertices = r.tessellation.points;
  surface.triangles = r.tessellation.triangles;
  surface.channels = r.channels == 1 ? 1 : 3;
  for (size_t p = 0; p < r.tessellation.points.size(); ++p) {
    for (int c = 0; c < surface.channels; ++c) {
      surface.colors.push_back(static_cast<float>(std::clamp(r.grey[p * r.channels + c], 0.0, 255.0)));
    }
  }
  for (double s : nodes.sigma) surface.sigma.push_back(static_cast<float>(s));
  surface.views = nodes.views;
  surface.origin = block.origin;
  surface.crs = block.crs;
  return surface;
}

MeshData SurfaceMeshData(const Reconstruction& r, const NodeAttributes& nodes) {
  MeshData mesh;
  mesh.vertices = r.tessellation.points;
  mesh.faces = r.tessellation.triangles;
  for (size_t p = 0; p < r.tessellation.points.size(); ++p) {
    Eigen::Vector3f colour;
    for (int c = 0; c < 3; ++c) {
      colour[c] = static_cast<float>(std::clamp(r.grey[p * r.channels + std::min(c, r.channels - 1)], 0.0, 255.0));
    }
    mesh.colors.push_back(colour);
  }
  for (double s : nodes.sigma) mesh.sigma.push_back(static_cast<float>(s));
  mesh.views = nodes.views;
  return mesh;
}

}  // namespace

ExportSurface MakeExportSurface(const Reconstruction& r, const ImageBlock& block) {
  return MakeExportSurface(r, block, NodeAttributes{NodeSigma(r), NodeViews(r)});
}

MeshData SurfaceMeshData(const Reconstruction& r) {
  return SurfaceMeshData(r, NodeAttributes{NodeSigma(r), NodeViews(r)});
}

MeshData TinMeshData(const Reconstruction& r) {
  MeshData mesh;
  for (auto vh : r.mesh.vertices()) {
    mesh.vertices.push_back(ToEigen(r.mesh.point(vh)));
    mesh.normals.push_back(ToEigen(r.mesh.normal(vh)));
    mesh.sigma.push_back(static_cast<float>(r.vertex_sigma[vh.idx()]));
    mesh.views.push_back(r.vertex_views[vh.idx()]);
  }
  for (const auto& f : FaceVertices(r.mesh)) mesh.faces.emplace_back(f[0], f[1], f[2]);
  return mesh;
}

std::vector<std::string> WriteProducts(const Reconstruction& r, const ImageBlock& block,
                                       const std::string& out_dir, const ProductOptions& options) {
  options.Check();
  const std::filesystem::path out(out_dir);
  std::filesystem::create_directories(out);
  std::vector<std::string> written;
  auto path = [&](const char* name) {
    written.push_back(name);
    return (out / name).string();
  };
  const NodeAttributes nodes{NodeSigma(r), NodeViews(r)};
  WritePly(path("surface.ply"), SurfaceMeshData(r, nodes));
  WritePly(path("tin.ply"), TinMeshData(r));
  if (options.glb || options.vrml) {
    const ExportSurface surface = MakeExportSurface(r, block, nodes);
    if (options.glb) WriteGlb(path("surface.glb"), surface);
    if (options.vrml) WriteVrml(path("surface.wrl"), surface);
  }
  if (options.rasters) {
    Eigen::AlignedBox3d box;
    for (const auto& p : r.tessellation.points) box.extend(p);
    const double pixel = options.raster_pixel > 0.0
                             ? options.raster_pixel
                             : (r.report.levels.empty() ? 0.1 : r.report.levels.back().ground_pixel);
    const RasterGrid grid = RasterGrid::Covering(box.min().head<2>(), box.max().head<2>(), pixel);
    const SurfaceScene scene(r.tessellation);
    const TopView top = CastTopView(scene, r.tessellation, grid);
    GeoReference geo;
    geo.origin = block.origin;
    geo.crs = block.crs;
    WriteGeoTiff(path("dsm.tif"), MakeDsm(top), geo);
    WriteGeoTiff(path("ortho.tif"), MakeOrthophoto(top, r.tessellation, r.grey, r.channels), geo);
    WriteGeoTiff(path("sigma.tif"), MakeSigmaRaster(top, r.tessellation, nodes.sigma), geo);
  }
  WriteFileAtomically(path("report.json"), r.report.Json() + "\n");
  return written;
}

}  // namespace facets
