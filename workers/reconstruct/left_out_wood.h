// SPDX-License-Identifier: Apache-2.0
// The wood the cameras saw that the vine model leaves out (reconstruction, after step 8): the
// stretches of the canes given to connect (connect.h) that lie in no cane, head, wire or post of
// the model -- a neighbour's canes dropped as leaves, canes with no likely parent, canes that
// hang on no tree. They go into VineModel::obstacles, so that the planner avoids them as it
// avoids canes (a real arm would hit them) while phenomics, decisions and the accuracy metrics,
// which read only the canes, do not see them.
//
// Found by geometry, not from connect's bookkeeping: whatever connect drops, merges, extends or
// replaces, a seen stretch is left out exactly when no part of the model lies where it is.
// Thread-safe (pure).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/geometry.h"
#include "core/vine_model.h"

namespace vb::reconstruct {

struct LeftOutWoodOptions {
  // A point of a seen cane is in a model cane when it lies within this of the cane's surface
  // (the 10 mm within which the accuracy metrics take two canes for the same wood,
  // ARCHITECTURE.md) and runs along it: the seen cane's direction there within
  // same_wood_max_angle_deg of the model segment's. So a seen cane crossing a model cane is
  // not covered where it crosses (the planner lets the cutter touch the cut cane near the cut,
  // collision_scene.h IsCaneNear, and must not let it touch other wood there).
  double covered_within_m = 0.01;
  double same_wood_max_angle_deg = 30.0;
  // A point is in a head sphere, wire or post only when the seen cane's cross-section lies
  // inside it grown by this (distance to its axis + the seen radius <= its radius + this): a cane
  // beside a 1.5 mm wire is not the wire.
  double contained_tolerance_m = 0.003;
  // Stretches shorter than this are left out of the obstacles (the ragged ends of covered canes).
  double min_length_m = 0.03;
  // Seen canes are tested at points this far apart along them (and at both ends); a stretch is
  // grown by one step at each end (within the seen cane), so that it reaches into the covering
  // part of the model instead of stopping up to one step short of it.
  double sample_step_m = 0.005;

  // INVALID_ARGUMENT naming the field: each must be finite, covered_within_m >= 0,
  // same_wood_max_angle_deg in [0, 90], contained_tolerance_m >= 0, min_length_m >= 0,
  // sample_step_m in [0.001, 0.1].
  absl::Status Validate() const;
};

// The stretches of `seen` that are not in `model` (as above), each as a piece of one seen cane
// with its points and radii, cut where the model begins or ends (one sample step into it), at
// least min_length_m long; in the order of `seen`, base to tip along each. Seen canes that fail
// Polyline3::Validate are skipped. INVALID_ARGUMENT for invalid options.
absl::StatusOr<std::vector<WoodObstacle>> LeftOutWood(const std::vector<Polyline3>& seen,
                                                      const VineModel& model,
                                                      const LeftOutWoodOptions& options = {});

}  // namespace vb::reconstruct
