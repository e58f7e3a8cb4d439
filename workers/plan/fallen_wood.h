// SPDX-License-Identifier: Apache-2.0
// The vine as the arm finds it after some cuts: wood beyond a cut falls (the cut cane's part past
// the cut point, and every cane growing from that part, with their descendants), so later cut
// motions and paths need not avoid it. The rule is core/fallen_wood.h's, which the simulator's
// world update (sim/world.h) applies too; this adapter takes the planner's cuts (points).
// Thread-safe (pure function).
#pragma once

#include <span>

#include "core/cut_plan.h"
#include "core/vine_model.h"

namespace vb::plan {

// `model` after `cuts` (points on their canes' axes, platform frame): each cut at the arc length
// of its point's projection onto its cane (Polyline3::Project), then core/fallen_wood.h's
// AfterCuts: the lowest cut on a cane decides, a child whose base projects beyond the cut falls
// with all its descendants, a cut within kMinCaneStubM (core/vine_model.h) of a cane's base drops
// the whole cane, and canes of the head hang on the trunk's top (a cut of the trunk below its top
// drops the head). Cuts on canes absent from `model` are ignored. The result passes
// VineModel::Validate() if `model` does.
VineModel WithoutFallenWood(const VineModel& model, std::span<const Cut> cuts);

}  // namespace vb::plan
