// SPDX-License-Identifier: Apache-2.0
// Per-pixel unit rays of a calibrated camera, the renderer's exact model of lens distortion.
// Building a table inverts the distortion at every pixel (~0.1-0.5 s for 1280x1024), so tables
// are cached by calibration (RayTableFor) or built once and passed to Render explicitly.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/calibration.h"

namespace vb::sim {

struct RayF {
  float x = 0.0f, y = 0.0f, z = 0.0f;
};

// Immutable after construction; safe to share between threads.
class RayTable {
 public:
  // Rays through every pixel centre of `camera`, in the platform frame. Pixels whose ray cannot be
  // recovered (the distortion inverse does not converge, e.g. beyond the fold of the radial
  // polynomial) get a zero ray and render black.
  explicit RayTable(const CameraCalibration& camera);

  int width() const { return width_; }
  int height() const { return height_; }
  const RayF& at(int x, int y) const { return rays_[static_cast<size_t>(y) * width_ + x]; }
  const RayF* row(int y) const { return &rays_[static_cast<size_t>(y) * width_]; }
  // Number of pixels with a zero ray.
  int invalid_count() const { return invalid_count_; }
  // True if this table was built for a calibration with the same intrinsics, size and rotation
  // (the translation does not change ray directions).
  bool Matches(const CameraCalibration& camera) const;

 private:
  int width_ = 0;
  int height_ = 0;
  int invalid_count_ = 0;
  std::vector<double> key_;
  std::vector<RayF> rays_;
};

// The ray table of `camera`, from a small process-wide cache (the most recent 8 calibrations).
// Thread-safe; concurrent first requests for the same calibration may each build a table.
std::shared_ptr<const RayTable> RayTableFor(const CameraCalibration& camera);

}  // namespace vb::sim
