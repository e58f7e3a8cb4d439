// SPDX-License-Identifier: Apache-2.0
// A simulated stop: the vine in front of the rig with its ground truth, the neighbouring vines
// whose canes intrude into the view, the trellis, the backdrop and the lights. Platform frame
// (ARCHITECTURE.md): x along the row, y across it from the cameras toward the backdrop, z up,
// origin on the ground below the rig centre. Plain value type; thread-compatible.
#pragma once

#include <cstdint>
#include <vector>

#include "core/calibration.h"
#include "core/vine_model.h"
#include "Eigen/Core"

namespace vb::sim {

// A point light (the rig's LED flashes). Irradiance falls off with 1/d^2.
struct Light {
  Eigen::Vector3d position_in_platform = Eigen::Vector3d::Zero();
  double intensity = 1.0;  // relative; 1.0 gives a mid-grey cane at 0.8 m with default exposure
};

struct Scene {
  uint64_t seed = 0;        // vineyard seed the scene was generated from
  int vine_index = 0;       // index of the vine along the row
  double vine_position_m = 0.0;  // row position of the vine (= vine_index * spacing + jitter)

  // Ground truth of the vine being pruned: its canes, head, and the trellis wires and posts in
  // view. This is what ground_truth.json holds.
  VineModel vine;
  // Neighbouring vines (canes and heads only; wires/posts are in `vine`), in the same frame.
  std::vector<VineModel> neighbours;

  double backdrop_y_m = 1.25;  // the blue backdrop plane y = backdrop_y_m
  // The platform's fiducials (sim/fiducials.h): white discs printed on the backdrop, drawn at
  // their (x, z); their y is taken to be backdrop_y_m. Empty: none (the default).
  std::vector<Fiducial> fiducials;
  double ground_z_m = 0.0;     // the ground plane
  std::vector<Light> lights;
};

// Ground-truth label values of the simulator's label images (16-bit PNG, one per camera).
inline constexpr uint16_t kLabelBackground = 0;  // backdrop, ground, sky
inline constexpr uint16_t kLabelWire = 1;
inline constexpr uint16_t kLabelPost = 2;
inline constexpr uint16_t kLabelHead = 3;
inline constexpr uint16_t kLabelOtherVine = 4;  // canes or head of a neighbouring vine
inline constexpr uint16_t kLabelCaneBase = 1000;  // kLabelCaneBase + cane id (trunk included)

}  // namespace vb::sim
