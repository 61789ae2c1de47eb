// The products of a reconstruction (DESIGN.md section 1, "Out"): the tessellated
// surface with object grey values, per-node precision and view counts as PLY, glTF
// binary and VRML97; the TIN; a true orthophoto, DSM and sigma raster seen from above.
#pragma once

#include <string>
#include <vector>

#include "engine/reconstruction.h"
#include "io/image_block.h"
#include "io/ply_io.h"
#include "io/surface_export.h"

namespace facets {

struct ProductOptions {
  bool glb = true;
  bool vrml = true;
  bool rasters = true;          // ortho.tif, dsm.tif, sigma.tif
  double raster_pixel = 0.0;    // ground pixel of the rasters (m); 0 = the finest level's
  void Check() const;
};

// Per tessellation node: the TIN vertex values of the face that made the node,
// interpolated with the node's barycentrics (sigma) or their minimum (views).
std::vector<double> NodeSigma(const Reconstruction& r);
std::vector<int> NodeViews(const Reconstruction& r);

// The tessellated surface (one vertex per grey node, one triangle per grey facet): the
// object grey model is linear per facet, so per-vertex colour represents it exactly.
ExportSurface MakeExportSurface(const Reconstruction& r, const ImageBlock& block);
MeshData SurfaceMeshData(const Reconstruction& r);
MeshData TinMeshData(const Reconstruction& r);

// Writes surface.ply, tin.ply, report.json and, as selected, surface.glb, surface.wrl,
// ortho.tif, dsm.tif, sigma.tif into out_dir (each atomically). Returns the file names.
std::vector<std::string> WriteProducts(const Reconstruction& r, const ImageBlock& block,
                                       const std::string& out_dir, const ProductOptions& options);

}  // namespace facets
