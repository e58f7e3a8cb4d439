// SPDX-License-Identifier: Apache-2.0
// The platform's fiducials: white discs printed on the backdrop at surveyed positions, around the
// border of what the rig sees, where the vine rarely reaches. They belong to the platform (the
// rig's calibration lists them, core/calibration.h); the renderer draws the scene's copy
// (Scene::fiducials) on the backdrop. Thread-safe (pure functions).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/calibration.h"

namespace vb::sim {

struct FiducialLayoutOptions {
  double backdrop_y_m = 1.25;   // the plane they are printed on (Scene::backdrop_y_m)
  double radius_m = 0.02;       // disc radius (12 px across at the image centre, 1.25 m away)
  // Columns at these x (m), each with discs at these z (m). The defaults ring the view of the
  // default rig (sim/rig.h) on the backdrop: a row along the top and one along the bottom, and
  // columns at both sides; all inside every camera's image, all but one at least 50 px inside
  // (with the rig before 2026-11-22 the top row's middle one was 44 px from the upper camera's
  // top edge; at z = 1.85 m the middle three were 20-36 px from it, too near for the detector's
  // window). The bottom row is at 0.4 m since the rig aims 0.1 m higher (at 0.3 m it was 19-48 px
  // from the lower cameras' bottom edges).
  std::vector<double> top_bottom_x_m = {-0.9, -0.45, 0.0, 0.45, 0.9};
  std::vector<double> top_bottom_z_m = {0.4, 1.80};
  std::vector<double> side_x_m = {-1.0, 1.0};
  std::vector<double> side_z_m = {0.55, 0.95, 1.35, 1.75};

  // INVALID_ARGUMENT naming the field: a non-finite value, radius_m outside (0, 0.2].
  absl::Status Validate() const;
};

// The fiducials of the layout, named fid0, fid1, ... (top/bottom rows first, then the sides).
absl::StatusOr<std::vector<Fiducial>> PlatformFiducials(const FiducialLayoutOptions& options = {});

}  // namespace vb::sim
