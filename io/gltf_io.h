// glTF 2.0 binary (.glb) export of a reconstructed surface (tinygltf).
//
// What the file holds (docs/PRODUCTS.md has the full description):
// - POSITION: float32 local coordinates (ExportSurface::vertices, relative to origin),
//   with exact min/max; NORMAL when the surface has normals (renormalised in float).
// - Colour (when the surface has colours), one of
//     kTexture: a texture atlas (io/surface_export.h, BuildTextureAtlas) as an sRGB PNG
//       inside the .glb, TEXCOORD_0, LINEAR filtering without mipmaps, material
//       KHR_materials_unlit (the grey values are measured radiance, not albedo to be
//       lit again). Vertices are duplicated per triangle corner (each corner has its
//       own atlas position).
//     kVertexColors: COLOR_0 as float32 VEC3, linear 0..1 (= colour / 255), shared
//       vertices, material KHR_materials_unlit.
//   Not both: glTF multiplies COLOR_0 into the base colour texture.
// - _SIGMA (float32 SCALAR, metres) and _VIEWS (float32 SCALAR, an integer count) per
//   vertex when present (application-specific attributes, names start with "_").
// - Georeferencing: the local origin and the CRS in asset.extras.facets and
//   scenes[0].extras.facets ({"origin": [x, y, z], "crs": "EPSG:...", "up": "Z"}), and
//   the origin as the translation (double) of node "facets_origin" that carries the mesh.
//   With y_up (default) that node is the child of node "facets_z_up_to_y_up", a
//   rotation of -90 degrees about X: object Z (up) becomes glTF +Y (up), so viewers show
//   the surface upright and Blender's importer (which turns Y-up back into Z-up) shows
//   the original object coordinates.
// - Index ranges: with max_primitive_vertices = 65535 (default) every primitive has at
//   most 65535 vertices and 16-bit indices (65535 itself is the primitive-restart value
//   and never used); larger meshes are split into several primitives of one mesh.
//   max_primitive_vertices = 0: one primitive, 32-bit indices when more than 65535
//   vertices.
#pragma once

#include <string>

#include "io/surface_export.h"

namespace facets {

enum class GlbColorMode { kTexture, kVertexColors };

struct GlbOptions {
  GlbColorMode color_mode = GlbColorMode::kTexture;
  // Vertices per primitive (see above); 0 = unlimited (32-bit indices), otherwise
  // 3..65535.
  int max_primitive_vertices = 65535;
  // Texels per side of an atlas cell holding two triangles (>= 5). 6 keeps the atlas at
  // 18 texels per triangle; larger cells only add texels (the colour is linear).
  int atlas_cell_px = 6;
  // Largest atlas side in texels; 16384 is what current desktop GPUs accept. A larger
  // atlas is refused (use kVertexColors for such meshes).
  int max_atlas_px = 16384;
  bool y_up = true;         // root rotation Z-up -> glTF Y-up (see above)
  bool write_sigma = true;  // _SIGMA when the surface has sigma
  bool write_views = true;  // _VIEWS when the surface has views
  std::string generator = "Facets";

  // Throws std::invalid_argument naming the bad field.
  void Check() const;
};

// Throws std::invalid_argument (message starts with path) when the surface fails
// ExportSurface::Check, has no triangles, or options are invalid;
// std::runtime_error naming the file when it cannot be written. Writes a unique temporary
// beside path and renames it at the end (io/atomic_file.h).
void WriteGlb(const std::string& path, const ExportSurface& surface, const GlbOptions& = {});

// The .glb file content in memory (what WriteGlb writes). `what` prefixes messages.
std::string GlbBytes(const ExportSurface& surface, const GlbOptions& options = {},
                     const std::string& what = "<glb>");

}  // namespace facets
