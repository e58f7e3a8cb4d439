// SPDX-License-Identifier: Apache-2.0
// The simulated camera rig: the default trinocular layout and calibration error.
// Thread-safe (pure functions).
#pragma once

#include <cstdint>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/calibration.h"

namespace vb::sim {

struct RigOptions {
  int camera_count = 3;            // cameras in a triangle (2 gives a horizontal pair)
  int image_width = 1280;
  int image_height = 1024;
  double horizontal_fov_deg = 100.0;   // wide lens: one vine and the gaps either side at 0.8 m
  double baseline_m = 0.22;            // triangle side (0.15-0.3 m)
  double rig_height_m = 1.05;          // z of the rig centre
  double distance_to_vine_plane_m = 0.8;   // across-row distance rig -> vine plane (y)
  double k1 = -0.28;                   // lens distortion of the simulated lenses
  double k2 = 0.09;
  double p1 = 0.0005;
  double p2 = -0.0003;
  double k3 = -0.012;
  bool toe_in = true;                  // cameras converge on the vine plane centre

  absl::Status Validate() const;
};

// The true calibration of the simulated rig. Cameras are named cam0, cam1, ...
absl::StatusOr<RigCalibration> MakeRig(const RigOptions& options = {});

// A copy of `rig` with calibration error: each camera's intrinsics and pose are perturbed so that
// reprojections move by about `error_px` pixels RMS (focal length, principal point, a small
// rotation). Deterministic in `seed`. error_px = 0 returns `rig` unchanged.
RigCalibration PerturbCalibration(const RigCalibration& rig, double error_px, uint64_t seed);

}  // namespace vb::sim
