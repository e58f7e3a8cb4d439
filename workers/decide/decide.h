// SPDX-License-Identifier: Apache-2.0
// The decide stage: a vine model and a pruning policy -> the cut plan (which canes to keep, which
// to leave as spurs, where to cut). Botterill et al. 2017 section 3.3: choose the cheapest
// pruning scheme under a learned linear cost (workers/decide/scheme.h), then place the cuts
// (workers/decide/cut_points.h). Deterministic. Thread-safe (pure functions).
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/cut_plan.h"
#include "core/deadline.h"
#include "core/pruning_policy.h"
#include "core/vine_model.h"
#include "workers/decide/scheme.h"

namespace vb::decide {

struct DecideOptions {
  SchemeWeights weights = DefaultSchemeWeights();  // the cost of a scheme
  // A cut point inside the head spheres slides outward along its cane, at most this far; a cut
  // that cannot leave the head within it is made at the farthest point and noted.
  double max_head_slide_m = 0.05;

  // INVALID_ARGUMENT naming the field ("options.weights.imbalance: not finite",
  // "options.max_head_slide_m: ...", which must lie in [0, 0.5]).
  absl::Status Validate() const;
};

struct Decision {
  CutPlan plan;
  Scheme scheme;
  SearchStats stats;
  // One line per event a supervisor should see ("cane 7: cut slid 0.012 m out of the head",
  // "only 1 candidate cane long enough to keep; policy asks for 2").
  std::vector<std::string> notes;
};

// INVALID_ARGUMENT naming the field for an invalid model (VineModel::Validate: parent cycles,
// unknown parents, NaN points, radii count mismatch), a model with no canes at all ("model:
// empty"; a valid model with canes always has its trunk), an invalid policy or options ("policy.x",
// "options.x"). DEADLINE_EXCEEDED / CANCELLED from `deadline`. A trunk without candidate canes is
// no error: the plan is empty and a note says why. plan.policy is `policy`; plan.keep and
// plan.spurs are the scheme's (sorted by id); plan.cuts come from PlaceCuts (cut_points.h).
absl::StatusOr<Decision> Decide(const VineModel& model, const PruningPolicy& policy,
                                const DecideOptions& options = {},
                                const Deadline& deadline = Deadline::Infinite());

}  // namespace vb::decide
