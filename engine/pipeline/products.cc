#include "engine/pipeline/products.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/gltf_io.h"
#include "io/preview.h"
#include "io/raster_io.h"
#include "io/vrml_io.h"
#include "visibility/surface_scene.h"
#include "visibility/top_view.h"

namespace facets {
void ProductOptions::SetFormats(const std::string& list) {
  ply = glb = vrml = ortho = dsm = sigma = preview = false;
  std::istringstream in(list);
  std::string name;
  int count = 0;
  while (std::getline(in, name, ',')) {
    if (name == "ply") ply = true;
    else if (name == "glb") glb = true;
    else if (name == "wrl") vrml = true;
    else if (name == "ortho") ortho = true;
    else if (name == "dsm") dsm = true;
    else if (name == "sigma") sigma = true;
    else if (name == "preview") preview = true;
    else throw std::invalid_argument("unknown product format '" + name + "' (known: " + kFormatNames + ")");
    ++count;
  }
  if (count == 0) throw std::invalid_argument(std::string("no product format given (known: ") + kFormatNames + ")");
}

void ProductOptions::Check() const {
  if (!(raster_pixel >= 0.0) || !std::isfinite(raster_pixel)) {
    throw std::invalid_argument("product options: raster_pixel must be >= 0");
  }
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

ProductSurface MakeProductSurface(const Reconstruction& r, const ImageBlock& block) {
  ProductSurface s;
  s.tessellation.points = r.tessellation.points;
  s.tessellation.triangles = r.tessellation.triangles;
  s.channels = r.channels == 1 ? 1 : 3;
  s.grey.reserve(r.tessellation.points.size() * s.channels);
  for (size_t p = 0; p < r.tessellation.points.size(); ++p) {
    // Clamped to the 8-bit range every product stores (PLY and atlas colours, the 8-bit
    // orthophoto): a value outside it (an extrapolating grey node at a poorly seen
    // border) would otherwise pull the orthophoto's interpolation differently from the
    // re-export of surface.ply.
    for (int c = 0; c < s.channels; ++c) {
      s.grey.push_back(std::clamp(r.grey[p * r.channels + c], 0.0, 255.0));
    }
  }
  s.sigma = NodeSigma(r);
  s.views = NodeViews(r);
  s.origin = block.origin;
  s.crs = block.crs;
  s.default_raster_pixel = r.report.levels.empty() ? 0.0 : r.report.levels.back().ground_pixel;
  s.up = r.report.camera_up;
  return s;
}

ProductSurface ProductSurfaceFromMesh(const MeshData& mesh, const std::string& what) {
  if (mesh.faces.empty()) throw std::runtime_error(what + ": the surface has no triangles");
  if (mesh.colors.empty()) {
    throw std::runtime_error(what + ": no vertex colours (object grey values): not a Facets surface.ply");
  }
  if (mesh.faces.size() % kSubTrianglesPerFace != 0) {
    throw std::runtime_error(what + ": " + std::to_string(mesh.faces.size()) +
                             " triangles, not " + std::to_string(kSubTrianglesPerFace) +
                             " grey facets per surface face: not a Facets surface.ply");
  }
  ProductSurface s;
  s.tessellation.points = mesh.vertices;
  s.tessellation.triangles = mesh.faces;
  const bool grey = std::all_of(mesh.colors.begin(), mesh.colors.end(), [](const Eigen::Vector3f& c) {
    return c[0] == c[1] && c[1] == c[2];
  });
  s.channels = grey ? 1 : 3;
  for (const Eigen::Vector3f& c : mesh.colors) {
    for (int k = 0; k < s.channels; ++k) s.grey.push_back(c[k]);
  }
  s.sigma.assign(mesh.sigma.begin(), mesh.sigma.end());
  s.views = mesh.views;
  s.origin = mesh.origin;
  s.crs = mesh.crs;
  return s;
}

MeshData SurfaceMeshData(const ProductSurface& s) {
  MeshData mesh;
  mesh.vertices = s.tessellation.points;
  mesh.faces = s.tessellation.triangles;
  for (size_t p = 0; p < s.tessellation.points.size(); ++p) {
    Eigen::Vector3f colour;
    for (int c = 0; c < 3; ++c) {
      colour[c] = static_cast<float>(std::clamp(s.grey[p * s.channels + std::min(c, s.channels - 1)], 0.0, 255.0));
    }
    mesh.colors.push_back(colour);
  }
  for (double v : s.sigma) mesh.sigma.push_back(static_cast<float>(v));
  mesh.views = s.views;
  mesh.origin = s.origin;
  mesh.crs = s.crs;
  return mesh;
}

ExportSurface MakeExportSurface(const ProductSurface& s) {
  ExportSurface surface;
  surface.vertices = s.tessellation.points;
  surface.triangles = s.tessellation.triangles;
  surface.channels = s.channels;
  surface.colors.reserve(s.grey.size());
  for (double g : s.grey) surface.colors.push_back(static_cast<float>(std::clamp(g, 0.0, 255.0)));
  for (double v : s.sigma) surface.sigma.push_back(static_cast<float>(v));
  surface.views = s.views;
  surface.origin = s.origin;
  surface.crs = s.crs;
  return surface;
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

MeshData TinGeometryData(const TinMesh& mesh) {
  MeshData data;
  for (auto vh : mesh.vertices()) {
    data.vertices.push_back(ToEigen(mesh.point(vh)));
    data.normals.push_back(ToEigen(mesh.normal(vh)));
  }
  for (const auto& f : FaceVertices(mesh)) data.faces.emplace_back(f[0], f[1], f[2]);
  return data;
}

std::vector<std::string> WriteSurfaceProducts(const ProductSurface& s, const std::string& out_dir,
                                              const ProductOptions& options) {
  options.Check();
  const double pixel = options.raster_pixel > 0.0 ? options.raster_pixel : s.default_raster_pixel;
  if (options.AnyRaster() && !(pixel > 0.0)) {
    throw std::invalid_argument(out_dir + ": rasters need a ground pixel size (give the raster pixel)");
  }
  if (options.sigma && s.sigma.size() != s.tessellation.points.size()) {
    throw std::invalid_argument(out_dir + ": the sigma raster needs one sigma per surface node");
  }
  const std::filesystem::path out(out_dir);
  std::filesystem::create_directories(out);
  std::vector<std::string> written;
  auto path = [&](const char* name) {
    written.push_back(name);
    return (out / name).string();
  };
  if (options.ply) WritePly(path("surface.ply"), SurfaceMeshData(s));
  if (options.glb || options.vrml || options.preview) {
    const ExportSurface surface = MakeExportSurface(s);
    if (options.glb) WriteGlb(path("surface.glb"), surface);
    if (options.vrml) WriteVrml(path("surface.wrl"), surface);
    if (options.preview) {
      PreviewOptions preview;
      preview.up = s.up;
      WritePreview(path("preview.png"), surface, preview);
    }
  }
  if (options.AnyRaster()) {
    Eigen::AlignedBox3d box;
    for (const auto& p : s.tessellation.points) box.extend(p);
    const RasterGrid grid = RasterGrid::Covering(box.min().head<2>(), box.max().head<2>(), pixel);
    const SurfaceScene scene(s.tessellation, /*refittable=*/false);
    const TopView top = CastTopView(scene, s.tessellation, grid);
    GeoReference geo;
    geo.origin = s.origin;
    geo.crs = s.crs;
    if (options.dsm) WriteGeoTiff(path("dsm.tif"), MakeDsm(top), geo);
    if (options.ortho) {
      WriteGeoTiff(path("ortho.tif"), MakeOrthophoto(top, s.tessellation, s.grey, s.channels), geo);
    }
    if (options.sigma) WriteGeoTiff(path("sigma.tif"), MakeSigmaRaster(top, s.tessellation, s.sigma), geo);
  }
  return written;
}

std::vector<std::string> WriteProducts(Reconstruction* r, const ImageBlock& block, const std::string& out_dir,
                                       const ProductOptions& options) {
  RunProfile& profile = r->report.profile;
  const ClockReading start = ReadClocks();
  std::vector<std::string> written;
  const std::filesystem::path out(out_dir);
  {
    const auto clock = profile.Stage(-1, 0, "products");
    const auto part = profile.Part("files");
    written = WriteSurfaceProducts(MakeProductSurface(*r, block), out_dir, options);
    if (options.ply) {
      MeshData tin = TinMeshData(*r);
      tin.origin = block.origin;
      tin.crs = block.crs;
      WritePly((out / "tin.ply").string(), tin);
      written.push_back("tin.ply");
    }
  }
  const ClockReading end = ReadClocks();
  profile.AddToTotal({end.wall - start.wall, end.cpu - start.cpu});
  WriteFileAtomically((out / "report.json").string(), r->report.Json() + "\n");
  written.push_back("report.json");
  return written;
}

}  // namespace facets
