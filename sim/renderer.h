// SPDX-License-Identifier: Apache-2.0
// Renders a simulated scene into a calibrated camera: canes as shaded cylinders with bark texture,
// LED lighting with 1/d^2 falloff and shadows on the backdrop, a blue backdrop with uneven
// shading, thin specular wires with sub-pixel coverage, lens distortion (through the calibration's
// exact pixel rays), sensor noise, and rgb8 or raw Bayer output; plus a ground-truth label image.
//
// Method: every cane/trunk polyline segment, wire piece and post piece is a capsule (posts:
// flat-ended cylinder), head spheres are spheres; each is ray-cast only inside its projected screen
// bounding box against the per-pixel rays of the camera (RayTable), keeping the nearest opaque hit
// and the nearest partially covering thin structure in front of it (coverage from the ray-to-axis
// distance against the pixel footprint, so a 3 mm wire at 0.8 m is a ~2 px line with mixed edge
// pixels). Rays that hit nothing meet the backdrop plane or the ground plane. Lighting: each
// scene light is a point light, irradiance intensity * (0.8 m / d)^2 * cos; so a single light of
// intensity 1 at the rig gives a cane at 0.8 m a mid-grey value (with N lights at the rig use
// intensity ~1/N each); plus `ambient`. Shadows of all casters fall on the backdrop, the ground and
// on canes behind other canes (render_shading.h).
//
// Thread-safe: Render() keeps no state between calls except the shared ray-table cache.
#pragma once

#include <cstdint>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/image.h"
#include "sim/scene.h"

namespace vb::sim {

class RayTable;

struct RenderOptions {
  PixelFormat pixel_format = PixelFormat::kRgb8;  // rgb8, mono8 or a Bayer mosaic
  double exposure = 1.0;          // relative exposure (scales all light)
  double read_noise_dn = 2.0;     // sensor read noise, standard deviation in digital numbers
  double shot_noise = 0.16;       // photon noise scale: sd = shot_noise * sqrt(value * 255) DN,
                                  // value = pixel value in [0, 1]; 0.16 gives ~1.8 DN at mid-grey
                                  // (a ~10k e- full well at 8 bits)
  bool shadows = true;
  bool texture = true;            // bark texture and backdrop unevenness
  double ambient = 0.12;          // ambient light fraction (sunlight leaking under the cover)
  double vignetting = 0.35;       // brightness drop at the image corners (fraction)
  double light_radius_m = 0.01;   // radius of each LED flash; sets the softness of shadow edges

  // INVALID_ARGUMENT naming the field: exposure not finite or <= 0; read_noise_dn, shot_noise,
  // ambient or light_radius_m not finite or < 0 (ambient also > 10); vignetting outside [0, 1);
  // pixel_format not one of the PixelFormat values.
  absl::Status Validate() const;
};

struct RenderedView {
  Image image;         // in options.pixel_format
  LabelImage labels;   // kLabel* values of sim/scene.h, per pixel: the nearest surface, or a thin
                       // structure in front of it covering >= half the pixel
};

// Renders `scene` as seen by `camera` (its true calibration). Noise is deterministic in
// `noise_seed` (and the same on every platform). Uses the shared ray-table cache (render_rays.h),
// so the first frame of a new calibration pays for building the table.
// INVALID_ARGUMENT for invalid options or camera calibration.
absl::StatusOr<RenderedView> Render(const Scene& scene, const CameraCalibration& camera,
                                    const RenderOptions& options, uint64_t noise_seed);

// As above with an explicit ray table, which must have been built for `camera`
// (INVALID_ARGUMENT otherwise).
absl::StatusOr<RenderedView> Render(const Scene& scene, const CameraCalibration& camera,
                                    const RayTable& rays, const RenderOptions& options,
                                    uint64_t noise_seed);

}  // namespace vb::sim
