// SPDX-License-Identifier: Apache-2.0
// Flags shared by `vinebot plan` and `vinebot bench plan`: the tool, the checker and the arm's
// mount, turned into the plan stage's robot, platform and options.
#pragma once

#include "absl/status/statusor.h"
#include "app/flags.h"
#include "workers/plan/plan_vine.h"
#include "workers/plan/robot_model.h"

namespace vb::app {

struct PlanSetup {
  plan::RobotModel robot;
  plan::PlatformGeometry platform;
  plan::PlanOptions options;
};

// --tool secateur|mill_end (default secateur), --checker primitives|fcl_primitives|fcl_mesh
// (default primitives), --calibration calibration.yaml (the stop's rig, capture bundle format:
// the cameras' capsules where it puts them, plan::PlatformAroundRig; without it
// plan::DefaultPlatform(), the simulator's default rig), --max-margin-m M, --path-time-limit-s T, --path-range-rad R,
// --shortcut-rounds N, --sweep-m S, --max-slide-m M, --last-resort-max-slide-m M,
// --max-tilt-deg D, --tilt-steps N,
// --max-roll-deg D, --roll-steps N, --cut-alternatives N, --cut-min-clearance-m M,
// --max-passes N, --path-max-tree-states N, --path-remember-failures true|false,
// --margin-fallback true|false,
// --retry-unreached true|false, --blend-transits true|false (defaults: PlanOptions'),
// --jaw-opening-m W
// (the secateur's, SecateurOptions' default), --joint-acceleration A (rad/s^2 for every joint;
// default JointLimits', 5 as in UR's ROS 2 MoveIt config; for what-if runs).
// --choose-motions-with-order true|false, --rolled-twins true|false, --undo-walled-in
// true|false (PlanOptions').
// INVALID_ARGUMENT naming the flag (NOT_FOUND for a missing calibration file).
absl::StatusOr<PlanSetup> ParsePlanSetup(Flags& flags);

absl::StatusOr<plan::CheckerKind> ParseCheckerKind(const std::string& name);

}  // namespace vb::app
