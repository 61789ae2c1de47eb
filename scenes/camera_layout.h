// Camera layouts of synthetic scenes -> an ImageBlock (cameras, poses, region of
// interest, mean terrain height). Images are named img_00.png, img_01.png, ...
#pragma once

#include <Eigen/Core>

#include "io/image_block.h"
#include "io/rigid3d.h"
#include "scenes/scene.h"

namespace facets {

// cam_from_world of a camera at `centre` looking at `target`; image x runs along
// direction x up and image y downwards (COLMAP frame: x right, y down, z forward).
// `up` must not be parallel to the viewing direction.
Rigid3d LookAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& target,
               const Eigen::Vector3d& up);

// Stereo: two nadir frames (square film frame, principal point at its centre) with
// base (1 - overlap) * frame * flying_height / focal along X, centred on the target.
// Block: rows x cols nadir images with forward (X) / side (Y) overlap, then obliques
// tilted oblique_tilt_deg off nadir looking N, E, S, W (up to 4 directions) at the
// target, oblique_strip of them per direction side by side (parallel axes, or all
// aimed at the target with oblique_convergent).
// Ring: cameras on rings around the target, looking at it. List: explicit cameras.
// crop_to_roi: each frame is cut to the pixel box of the ROI corners plus a margin
// (its own camera: the principal point moves, focal length stays).
ImageBlock BuildImageBlock(const Scene& scene);

}  // namespace facets
