// SPDX-License-Identifier: Apache-2.0
#include "app/plan_flags.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/plan/tool.h"

namespace vb::app {

absl::StatusOr<plan::CheckerKind> ParseCheckerKind(const std::string& name) {
  for (plan::CheckerKind kind : {plan::CheckerKind::kPrimitives, plan::CheckerKind::kFclPrimitives,
                                 plan::CheckerKind::kFclMesh}) {
    if (name == plan::CheckerKindName(kind)) return kind;
  }
  return absl::InvalidArgumentError(absl::StrCat(
      "--checker: unknown checker '", name, "' (expected primitives, fcl_primitives or fcl_mesh)"));
}

absl::StatusOr<PlanSetup> ParsePlanSetup(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const std::string tool, flags.String("tool", "mill_end"));
  VB_ASSIGN_OR_RETURN(const std::string checker, flags.String("checker", "primitives"));
  VB_ASSIGN_OR_RETURN(const double max_margin_m, flags.Double("max-margin-m", 0.03));
  VB_ASSIGN_OR_RETURN(const double path_time_limit_s, flags.Double("path-time-limit-s", 0.25));
  PlanSetup setup;
  plan::CutMotionOptions& cut = setup.options.cut_motion;
  VB_ASSIGN_OR_RETURN(cut.sweep_m, flags.Double("sweep-m", cut.sweep_m));
  VB_ASSIGN_OR_RETURN(cut.max_slide_m, flags.Double("max-slide-m", cut.max_slide_m));
  VB_ASSIGN_OR_RETURN(const double tilt_deg, flags.Double("max-tilt-deg", cut.max_tilt_rad * 180 / M_PI));
  VB_ASSIGN_OR_RETURN(const int64_t tilt_steps, flags.Int("tilt-steps", cut.tilt_steps));
  VB_ASSIGN_OR_RETURN(const int64_t passes, flags.Int("max-passes", setup.options.max_passes));
  cut.max_tilt_rad = tilt_deg * M_PI / 180;
  cut.tilt_steps = static_cast<int>(tilt_steps);
  setup.options.max_passes = static_cast<int>(passes);
  if (tool == "mill_end") {
    setup.robot = plan::DefaultUr5(plan::MillEndTool());
  } else if (tool == "secateur") {
    setup.robot = plan::DefaultUr5(plan::SecateurTool());
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat("--tool: unknown tool '", tool, "' (expected mill_end or secateur)"));
  }
  setup.platform = plan::DefaultPlatform();
  VB_ASSIGN_OR_RETURN(setup.options.checker, ParseCheckerKind(checker));
  setup.options.home = plan::DefaultHome();
  setup.options.margins.max_margin_m = max_margin_m;
  setup.options.path.time_limit_s = path_time_limit_s;
  if (absl::Status s = setup.options.Validate(); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat("plan flags: ", s.message()));
  return setup;
}

}  // namespace vb::app
