// SPDX-License-Identifier: Apache-2.0
// Internal to PlanVine (plan_vine.cc): the timing step, each planned leg turned into timed
// segments of the trajectory (docs/plan.md, "The plan stage", step 8). Every segment starts and
// ends at rest. Not thread-safe (the checker and prover belong to the calling thread).
#pragma once

#include <span>

#include "absl/status/status.h"
#include "core/cut_plan.h"
#include "core/trajectory.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/motion_prover.h"
#include "workers/plan/plan_vine.h"
#include "workers/plan/robot_model.h"

namespace vb::plan {

// Appends a transit from rest to rest, blended through its waypoints (blend.h) where the blends
// are free in `checker` (the scene it was planned in) and the chords between its samples that
// pass through a blend are proven free by `proof` (the scene without margins; the other chords
// lie on the waypoint segments, proven when the path was accepted); otherwise it stops at each
// waypoint. Counts the blends and checks into `stats`. Errors of the time parameterisation
// (INVALID_ARGUMENT naming the field).
absl::Status AppendTransit(std::span<const Joints> waypoints, CollisionChecker* checker,
                           MotionProver* proof, const PlanOptions& options,
                           const JointLimits& limits, PlanStats& stats, Trajectory* out);

// Appends a cut stroke, at rest at its ends. Mill end: the part of the sweep whose TCP is within
// the cane's radius plus options.cut_feed_margin_m of the cut point moves at the feed rate
// (options.cut_speed_fraction of the velocity limits), the rest at the full limits. Secateur:
// the jaws close with the arm at rest at the cut. Errors as AppendTransit.
absl::Status AppendStroke(const CutMotion& motion, const Cut& cut, const RobotModel& robot,
                          const PlanOptions& options, Trajectory* out);

}  // namespace vb::plan
