// VRML97 (.wrl) export of a reconstructed surface.
//
// One Transform whose translation is the local origin (global = origin + local), holding
// one Shape with an IndexedFaceSet: Coordinate (local coordinates, fixed 6 decimals =
// micrometres for metres), coordIndex (counter-clockwise, ccw TRUE), Normal when the
// surface has normals, solid FALSE (open surfaces are seen from both sides). Colour, when
// the surface has colours, is one of
//   kTexture: the texture atlas of io/surface_export.h (BuildTextureAtlas, same layout
//     as the .glb) written as an sRGB PNG beside the .wrl ("<stem>_atlas.png", referred
//     to by a relative url) with TextureCoordinate/texCoordIndex;
//   kVertexColors: per-vertex Color, the linear 0..255 values sRGB-encoded and scaled
//     to 0..1 (VRML browsers put colours on the display unconverted, so display-encoded
//     values show the measured grey values as they look in the images).
// The Appearance has no Material: VRML97 then renders the texture or the colours
// unlit, as the glTF export does with KHR_materials_unlit. The origin and the CRS are
// also named in a WorldInfo node. Numbers are written locale-independently.
#pragma once

#include <string>

#include "io/surface_export.h"

namespace facets {

enum class VrmlColorMode { kTexture, kVertexColors };

struct VrmlOptions {
  VrmlColorMode color_mode = VrmlColorMode::kTexture;
  int atlas_cell_px = 6;        // as GlbOptions::atlas_cell_px
  int max_atlas_px = 16384;     // as GlbOptions::max_atlas_px
  int coordinate_decimals = 6;  // 6 = micrometres for metres; 1..12

  // Throws std::invalid_argument naming the bad field.
  void Check() const;
};

// Writes path (and, textured, the atlas PNG beside it, first) via temporary files and
// renames. Throws std::invalid_argument (message starts with path) for a bad surface
// (ExportSurface::Check, no triangles) or options, std::runtime_error naming the file
// when it cannot be written.
void WriteVrml(const std::string& path, const ExportSurface& surface,
               const VrmlOptions& options = {});

// The file name of the atlas WriteVrml writes for `path` ("dir/x.wrl" ->
// "dir/x_atlas.png").
std::string VrmlAtlasPath(const std::string& path);

// The .wrl text; `texture_url` is the atlas url written into ImageTexture (textured
// mode). The atlas itself is returned through `atlas` when not null.
std::string VrmlText(const ExportSurface& surface, const VrmlOptions& options,
                     const std::string& texture_url, const std::string& what = "<wrl>",
                     TextureAtlas* atlas = nullptr);

}  // namespace facets
