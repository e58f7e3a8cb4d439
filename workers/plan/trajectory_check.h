// SPDX-License-Identifier: Apache-2.0
// An independent re-check of a planned trajectory: every segment is interpolated densely and
// checked against the vine as it is at that moment (wood beyond each cut already made has fallen,
// fallen_wood.h), without safety margins, by any checker -- the FCL meshes in the benchmark.
// Thread-safe (pure function).
#pragma once

#include <span>
#include <vector>

#include "core/cut_plan.h"
#include "core/trajectory.h"
#include "core/vine_model.h"
#include "workers/plan/plan_vine.h"
#include "workers/plan/robot_model.h"

namespace vb::plan {

// Number of colliding configurations on `trajectory` (0: collision-free), checking so that no
// point of the arm moves more than `max_step_m` between checks. Transit segments are checked
// against the whole current vine; a cut segment may touch its own cane within `cut_radius_m` of
// its cut (CollisionScene::WithoutCaneNear). `cuts` are PlanResult::cuts (points as made).
// `bad_segments` (optional) receives the count per segment. INVALID_ARGUMENT-worthy input (a
// model that does not build a scene) counts as one collision per segment.
int64_t CountTrajectoryCollisions(const Trajectory& trajectory, std::span<const Cut> cuts,
                                  const VineModel& model, const PlatformGeometry& platform,
                                  const RobotModel& robot, CheckerKind checker, double max_step_m,
                                  double cut_radius_m, std::vector<int>* bad_segments = nullptr);

}  // namespace vb::plan
