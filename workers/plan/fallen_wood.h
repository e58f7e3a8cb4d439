// SPDX-License-Identifier: Apache-2.0
// The vine as the arm finds it after some cuts: wood beyond a cut falls (the cut cane's part past
// the cut point, and every cane growing from that part, with their descendants), so later cut
// motions and paths need not avoid it. The same rule as the simulator's world update
// (sim/world.h), written against the model alone. Thread-safe (pure function).
#pragma once

#include <span>

#include "core/cut_plan.h"
#include "core/vine_model.h"

namespace vb::plan {

// `model` after `cuts` (points on their canes' axes, platform frame). A cut cane keeps the part of
// its polyline from its base to the point of its axis nearest the cut; a child whose base projects
// onto its parent's axis beyond the cut falls with all its descendants, as does the whole cut cane
// when the cut is within kMinCaneStubM (core/vine_model.h) of its base. Children of the trunk
// (canes from the head) never fall with a cut of another cane. Cuts on canes absent from `model` are ignored. The result
// passes VineModel::Validate() if `model` does.
VineModel WithoutFallenWood(const VineModel& model, std::span<const Cut> cuts);

}  // namespace vb::plan
