// SPDX-License-Identifier: Apache-2.0
// Renders a simulated scene into a calibrated camera: canes as shaded cylinders with bark texture,
// LED lighting with 1/d^2 falloff and shadows on the backdrop, a blue backdrop with uneven
// shading, thin specular wires with sub-pixel coverage, lens distortion (through the calibration's
// exact pixel rays), sensor noise, and rgb8 or raw Bayer output; plus a ground-truth label image.
// Thread-safe: Render() keeps no state between calls.
#pragma once

#include <cstdint>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/image.h"
#include "sim/scene.h"

namespace vb::sim {

struct RenderOptions {
  PixelFormat pixel_format = PixelFormat::kRgb8;  // rgb8, mono8 or a Bayer mosaic
  double exposure = 1.0;          // relative exposure (scales all light)
  double read_noise_dn = 2.0;     // sensor read noise, standard deviation in digital numbers
  double shot_noise = 0.04;       // photon noise scale: sd = shot_noise * sqrt(value * 255) DN
  bool shadows = true;
  bool texture = true;            // bark texture and backdrop unevenness
  double ambient = 0.12;          // ambient light fraction (sunlight leaking under the cover)
  double vignetting = 0.35;       // brightness drop at the image corners (fraction)

  absl::Status Validate() const;
};

struct RenderedView {
  Image image;         // in options.pixel_format
  LabelImage labels;   // kLabel* values of sim/scene.h, per pixel (nearest surface)
};

// Renders `scene` as seen by `camera` (its true calibration). Noise is deterministic in
// `noise_seed`. INVALID_ARGUMENT for invalid options or camera calibration.
absl::StatusOr<RenderedView> Render(const Scene& scene, const CameraCalibration& camera,
                                    const RenderOptions& options, uint64_t noise_seed);

}  // namespace vb::sim
