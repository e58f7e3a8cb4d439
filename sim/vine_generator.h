// SPDX-License-Identifier: Apache-2.0
// Synthetic dormant vines with ground truth. A vineyard row is a pure function of a seed: vine k
// stands near x = k * spacing along the row; a stop at vine k puts it at the platform origin
// (x = 0) and its neighbours k-1, k+1 at about -/+ spacing, so their canes intrude into view.
// Vine structure after Botterill et al., "A Robot System for Pruning Grape Vines" (J. Field
// Robotics 2017); see sim/vine_plant.h and sim/vine_cane_growth.h for the growth model.
// Thread-safe (no shared state).
#pragma once

#include <cstdint>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "sim/scene.h"

namespace vb::sim {

struct VineGeneratorOptions {
  double vine_spacing_m = 1.8;            // distance between vines along the row
  double vine_plane_y_m = 0.8;            // across-row distance of the vine plane from the rig
  double trunk_height_min_m = 0.6;        // trunk height range (head sits on top)
  double trunk_height_max_m = 1.2;
  double trunk_diameter_min_m = 0.03;     // trunk diameter range
  double trunk_diameter_max_m = 0.06;
  int canes_min = 8;                      // canes growing from the head and trunk
  int canes_max = 25;
  double fork_probability = 0.25;         // chance a cane forks a secondary cane
  double cane_length_min_m = 0.2;         // cane length range
  double cane_length_max_m = 1.8;
  double cane_diameter_min_m = 0.004;     // base diameter range (tapering to the tip)
  double cane_diameter_max_m = 0.015;
  int old_spurs_min = 1;                  // old spurs (short stubs) on the head
  int old_spurs_max = 4;
  double head_radius_m = 0.05;            // typical head half-size
  double fruiting_wire_min_m = 0.9;       // fruiting wire height range
  double fruiting_wire_max_m = 1.0;
  int foliage_wires_min = 2;              // wires above the fruiting wire (3-4 wires in all)
  int foliage_wires_max = 3;
  double wire_radius_m = 0.0015;
  double post_spacing_m = 6.0;            // a post every ~6 m along the row
  double post_radius_m = 0.04;
  double post_height_m = 1.9;
  double backdrop_y_m = 1.25;             // blue backdrop across the row
  bool neighbours = true;                 // include neighbouring vines

  // INVALID_ARGUMENT naming the field for empty ranges, non-positive sizes, etc.
  absl::Status Validate() const;
};

// Generates the scene of a stop at vine `vine_index` of the row generated from `seed`.
// Deterministic in (seed, vine_index, options), portably (sim/vine_random.h). INVALID_ARGUMENT
// for invalid options (INTERNAL only if the generator produced a model failing Validate()).
// The platform origin is at the vine's nominal row position vine_index * vine_spacing_m; the vine
// stands at x = jitter (|jitter| <= 0.1 m), scene.vine_position_m = vine_index * spacing + jitter.
// scene.vine holds: the trunk (id 1, from z = 0 up to the head), canes (kind cane) and old spurs
// (kind spur) with ids 2, 3, ... (parents before children; a cane's first point lies on its
// parent's axis or on a head sphere's surface), the head spheres, the row's wires (id 1 is the
// fruiting wire; they span x in [-2.5, 2.5] m with sag between posts) and every post with
// |x| <= 2.5 m (sim/trellis.h). scene.neighbours are vines vine_index - 1 and + 1 (in that order)
// exactly as their own stops generate them, shifted by -/+ vine_spacing_m: canes and head only.
// scene.lights are the rig's four LED flashes (x = -/+0.3, y = 0.05, z = 0.7 and 1.4, intensity
// 0.5 each).
absl::StatusOr<Scene> GenerateScene(uint64_t seed, int vine_index,
                                    const VineGeneratorOptions& options = {});

}  // namespace vb::sim
