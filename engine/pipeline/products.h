// The products of a reconstruction (DESIGN.md section 1, "Out"): the tessellated
// surface with object grey values, per-node precision and view counts as PLY, glTF
// binary and VRML97; the TIN; a true orthophoto, DSM and sigma raster seen from above;
// a preview picture.
//
// `facets reconstruct` writes them from the Reconstruction, `facets export` re-writes
// them from a finished run's surface.ply: both go through ProductSurface and
// WriteSurfaceProducts, so the two commands write the same files with the same writers.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "engine/pipeline/reconstruction.h"
#include "io/image_block.h"
#include "io/ply_io.h"
#include "io/surface_export.h"
#include "mesh/tessellation.h"

namespace facets {

struct ProductOptions {
  bool ply = true;      // surface.ply
  bool glb = true;      // surface.glb
  bool vrml = true;     // surface.wrl (+ surface_atlas.png)
  bool ortho = true;    // ortho.tif
  bool dsm = true;      // dsm.tif
  bool sigma = true;    // sigma.tif
  bool preview = true;  // preview.png
  double raster_pixel = 0.0;  // ground pixel of the rasters (m); 0 = ProductSurface's default

  bool AnyRaster() const { return ortho || dsm || sigma; }
  // Selects exactly the formats of a comma-separated list of kFormatNames, e.g.
  // "glb,wrl,ortho". Throws std::invalid_argument naming an unknown or missing format.
  void SetFormats(const std::string& list);
  void Check() const;
};

// The names SetFormats accepts, in writing order.
inline constexpr const char* kFormatNames = "ply,glb,wrl,ortho,dsm,sigma,preview";

// Everything the surface products are made of.
struct ProductSurface {
  // Grey nodes (points, local object coordinates) and grey facets (triangles,
  // kSubTrianglesPerFace per geometry face, in face order: what SurfaceScene needs for
  // the top view of the rasters). Only points and triangles are used.
  Tessellation tessellation;
  int channels = 1;            // 1 grey, 3 RGB
  std::vector<double> grey;    // node-major: grey[node * channels + c], 0..255
  std::vector<double> sigma;   // per node, m; empty = unknown
  std::vector<int> views;      // per node; empty = unknown
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // global = origin + local
  std::string crs;                                    // "" unknown
  double default_raster_pixel = 0.0;  // m; 0 = none (then ProductOptions::raster_pixel is needed)
  // Up in the preview of a facade (PreviewOptions::up): the cameras' mean up direction
  // (ReconstructionReport::camera_up; `facets export` reads it from report.json).
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
};

// Per tessellation node: the TIN vertex values of the face that made the node,
// interpolated with the node's barycentrics (sigma) or their minimum (views).
std::vector<double> NodeSigma(const Reconstruction& r);
std::vector<int> NodeViews(const Reconstruction& r);

// The product surface of a reconstruction: georeference of the block, raster pixel =
// the finest level's ground pixel.
ProductSurface MakeProductSurface(const Reconstruction& r, const ImageBlock& block);
// The product surface of a run's surface.ply (as SurfaceMeshData wrote it; colours are
// 8-bit there, so grey values come back rounded). Grey when every colour has R = G = B.
// Throws std::runtime_error starting with `what` when the mesh has no colours or its
// triangle count is not a multiple of kSubTrianglesPerFace (not a Facets surface).
ProductSurface ProductSurfaceFromMesh(const MeshData& mesh, const std::string& what);

// surface.ply content: one vertex per grey node with colour (grey repeated in R, G, B),
// sigma, views, origin and CRS (header comments).
MeshData SurfaceMeshData(const ProductSurface& surface);
// What the glb / wrl writers take (one vertex per grey node, one triangle per facet:
// the grey model is linear per facet, so per-vertex colour represents it exactly).
ExportSurface MakeExportSurface(const ProductSurface& surface);
MeshData TinMeshData(const Reconstruction& r);
// A TIN's vertices, vertex normals and triangles (no sigma, no views): the per-level
// meshes of `facets reconstruct --keep-levels`.
MeshData TinGeometryData(const TinMesh& mesh);

// Writes the selected surface products (surface.ply, surface.glb, surface.wrl,
// ortho.tif, dsm.tif, sigma.tif, preview.png) into out_dir, each atomically, and
// returns the file names written. Throws std::invalid_argument when a raster is
// selected without a pixel size, or the sigma raster without sigma values.
std::vector<std::string> WriteSurfaceProducts(const ProductSurface& surface,
                                              const std::string& out_dir,
                                              const ProductOptions& options);

// WriteSurfaceProducts of the reconstruction, plus tin.ply (with options.ply) and
// report.json. Returns the file names.
// The files' seconds go into r->report.profile (stage "products", part "files") before
// report.json is written.
std::vector<std::string> WriteProducts(Reconstruction* r, const ImageBlock& block, const std::string& out_dir,
                                       const ProductOptions& options);

}  // namespace facets
