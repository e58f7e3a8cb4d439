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

// --tool mill_end|secateur (default mill_end), --checker primitives|fcl_primitives|fcl_mesh
// (default primitives), --max-margin-m M (default 0.03), --path-time-limit-s T (default 0.25).
// INVALID_ARGUMENT naming the flag.
absl::StatusOr<PlanSetup> ParsePlanSetup(Flags& flags);

absl::StatusOr<plan::CheckerKind> ParseCheckerKind(const std::string& name);

}  // namespace vb::app
