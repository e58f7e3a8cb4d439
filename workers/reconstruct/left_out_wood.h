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
  // A point of a seen cane is in the model when it lies within this of the surface of a model
  // cane, head sphere, wire or post (the 10 mm within which the accuracy metrics take two canes
  // for the same wood, ARCHITECTURE.md).
  double covered_within_m = 0.01;
  // Stretches shorter than this are left out of the obstacles (the ragged ends of covered canes).
  double min_length_m = 0.03;
  // Seen canes are tested at points this far apart along them (and at both ends).
  double sample_step_m = 0.005;

  // INVALID_ARGUMENT naming the field: each must be finite, covered_within_m >= 0,
  // min_length_m >= 0, sample_step_m in [0.001, 0.1].
  absl::Status Validate() const;
};

// The stretches of `seen` that are not in `model` (as above), each as a piece of one seen cane
// with its points and radii, cut where the model begins or ends (to within sample_step_m), at
// least min_length_m long; in the order of `seen`, base to tip along each. Seen canes that fail
// Polyline3::Validate are skipped. INVALID_ARGUMENT for invalid options.
absl::StatusOr<std::vector<WoodObstacle>> LeftOutWood(const std::vector<Polyline3>& seen,
                                                      const VineModel& model,
                                                      const LeftOutWoodOptions& options = {});

}  // namespace vb::reconstruct
