// A picture of a reconstructed surface for people (preview.png beside the products):
// two panels side by side, both from one oblique viewpoint, the left one Lambert-shaded
// (shows the geometry), the right one with the object grey values / colours (shows what
// the images saw). Rendered in software with a z-buffer: no GPU, no new dependency;
// OpenImageIO writes the PNG.
//
// Projection: orthographic along the view direction, scaled so the whole surface fits
// a panel (no perspective: the picture has no camera distance to choose, and parallel
// lines stay parallel as on a map). Triangles are seen from both sides (open
// surfaces); the shading normal is the facet normal turned towards the viewer.
//
// Facades: azimuths and elevations are given for a surface that faces +Z (terrain,
// roofs). A surface whose area-weighted mean normal is tilted more than
// facade_min_tilt_deg from the Z axis (a facade seen from the street; Z need not even
// be up) is shown in its own frame instead: the mean normal plays the zenith, `up`
// projected onto the surface's plane plays north (the top of the picture), so the
// viewer looks at the front from facade_view_elevation_deg above its plane and the
// light falls on the front as it falls on a map. Closed surfaces (mean normal near
// zero) keep the Z frame.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "io/surface_export.h"

namespace facets {

struct PreviewOptions {
  int panel_width = 600;   // the picture is 2 * panel_width x panel_height
  int panel_height = 500;
  // Where the viewer is, seen from the surface: azimuth clockwise from north (+Y) and
  // elevation above the horizon. 225 / 35: from the south-west, looking down obliquely.
  double view_azimuth_deg = 225.0;
  double view_elevation_deg = 35.0;
  // The facade frame (see above): on when the mean normal is tilted more than this from
  // Z and the surface is open (|mean normal| >= facade_min_flatness of its area).
  bool facade_frame = true;
  double facade_min_tilt_deg = 45.0;
  double facade_min_flatness = 0.3;
  double facade_view_elevation_deg = 60.0;
  // World up for the facade frame's picture (the products set the cameras' mean up
  // direction; Z is not up in every street-level model). Need not be unit length.
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  // Where the light comes from (shaded panel): north-west, as on shaded relief maps.
  double light_azimuth_deg = 315.0;
  double light_elevation_deg = 45.0;
  double ambient = 0.15;    // shaded panel: 255 * (ambient + (1 - ambient) * max(0, n.l))
  int supersampling = 3;    // samples per pixel side (anti-aliasing)
  int margin_px = 10;       // free border around the surface in each panel
  // Not a grey, so that no surface pixel of a grey surface equals it exactly.
  std::array<std::uint8_t, 3> background = {222, 232, 242};

  // Throws std::invalid_argument naming the bad field.
  void Check() const;
};

struct PreviewImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // row-major, 3 bytes per pixel, 8-bit display values
};

// The directions a preview is rendered with: towards the viewer, towards the light,
// and the world direction that is up in the picture.
struct PreviewFrame {
  Eigen::Vector3d toward, light, vertical;
  bool facade = false;  // the facade frame was chosen
};
PreviewFrame ChoosePreviewFrame(const ExportSurface& surface, const PreviewOptions& options);

// Renders the two panels. Colours (linear 0..255 object grey values, which are image
// grey values) are shown as they are, like the images show them; without colours the
// right panel is mid grey. Throws std::invalid_argument starting with `what` for a
// surface that fails ExportSurface::Check or has no triangles.
PreviewImage RenderPreview(const ExportSurface& surface, const PreviewOptions& options = {},
                           const std::string& what = "<preview>");

// RenderPreview written as an 8-bit RGB PNG (via a unique temporary and a rename). Throws
// std::runtime_error naming the file when it cannot be written.
void WritePreview(const std::string& path, const ExportSurface& surface,
                  const PreviewOptions& options = {});

}  // namespace facets
