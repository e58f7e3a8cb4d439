// SPDX-License-Identifier: Apache-2.0
#include "app/plan_flags.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "workers/capture/bundle.h"
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
  PlanSetup setup;
  plan::PlanOptions& o = setup.options;
  plan::CutMotionOptions& cut = o.cut_motion;
  VB_ASSIGN_OR_RETURN(const std::string tool, flags.String("tool", "secateur"));
  VB_ASSIGN_OR_RETURN(const std::string checker, flags.String("checker", "primitives"));
  VB_ASSIGN_OR_RETURN(const std::string calibration, flags.String("calibration", ""));
  VB_ASSIGN_OR_RETURN(o.margins.max_margin_m, flags.Double("max-margin-m", o.margins.max_margin_m));
  VB_ASSIGN_OR_RETURN(o.path.time_limit_s, flags.Double("path-time-limit-s", o.path.time_limit_s));
  VB_ASSIGN_OR_RETURN(o.path.range_rad, flags.Double("path-range-rad", o.path.range_rad));
  VB_ASSIGN_OR_RETURN(const int64_t rounds, flags.Int("shortcut-rounds", o.path.shortcut_rounds));
  VB_ASSIGN_OR_RETURN(const int64_t max_states,
                      flags.Int("path-max-tree-states", o.path.max_tree_states));
  VB_ASSIGN_OR_RETURN(const int64_t flip_states,
                      flags.Int("path-flip-max-tree-states", o.path.flip_max_tree_states));
  VB_ASSIGN_OR_RETURN(o.path.tree_max_step_m,
                      flags.Double("path-tree-max-step-m", o.path.tree_max_step_m));
  VB_ASSIGN_OR_RETURN(o.path.remember_failures,
                      flags.Bool("path-remember-failures", o.path.remember_failures));
  VB_ASSIGN_OR_RETURN(o.margin_fallback, flags.Bool("margin-fallback", o.margin_fallback));
  VB_ASSIGN_OR_RETURN(o.retry_unreached, flags.Bool("retry-unreached", o.retry_unreached));
  VB_ASSIGN_OR_RETURN(const int64_t passes, flags.Int("max-passes", o.max_passes));
  VB_ASSIGN_OR_RETURN(cut.sweep_m, flags.Double("sweep-m", cut.sweep_m));
  VB_ASSIGN_OR_RETURN(cut.max_slide_m, flags.Double("max-slide-m", cut.max_slide_m));
  VB_ASSIGN_OR_RETURN(o.last_resort_max_slide_m,
                      flags.Double("last-resort-max-slide-m", o.last_resort_max_slide_m));
  VB_ASSIGN_OR_RETURN(const double tilt_deg,
                      flags.Double("max-tilt-deg", cut.max_tilt_rad * 180 / M_PI));
  VB_ASSIGN_OR_RETURN(const int64_t tilt_steps, flags.Int("tilt-steps", cut.tilt_steps));
  // Every joint's acceleration limit (default JointLimits', 5 rad/s^2): for what-if runs.
  VB_ASSIGN_OR_RETURN(const double acceleration,
                      flags.Double("joint-acceleration", plan::JointLimits().max_acceleration[0]));
  VB_ASSIGN_OR_RETURN(o.blend_transits, flags.Bool("blend-transits", o.blend_transits));
  VB_ASSIGN_OR_RETURN(const double roll_deg,
                      flags.Double("max-roll-deg", cut.max_roll_rad * 180 / M_PI));
  VB_ASSIGN_OR_RETURN(const int64_t roll_steps, flags.Int("roll-steps", cut.roll_steps));
  VB_ASSIGN_OR_RETURN(const int64_t alternatives,
                      flags.Int("cut-alternatives", cut.alternatives));
  VB_ASSIGN_OR_RETURN(o.choose_motions_with_order,
                      flags.Bool("choose-motions-with-order", o.choose_motions_with_order));
  VB_ASSIGN_OR_RETURN(o.rolled_twins, flags.Bool("rolled-twins", o.rolled_twins));
  VB_ASSIGN_OR_RETURN(o.undo_walled_in, flags.Bool("undo-walled-in", o.undo_walled_in));
  o.path.shortcut_rounds = static_cast<int>(rounds);
  if (max_states < 0 || max_states > 100000000)
    return absl::InvalidArgumentError("--path-max-tree-states must be in [0, 1e8]");
  o.path.max_tree_states = static_cast<int>(max_states);
  if (flip_states < 0 || flip_states > 100000000)
    return absl::InvalidArgumentError("--path-flip-max-tree-states must be in [0, 1e8]");
  o.path.flip_max_tree_states = static_cast<int>(flip_states);
  o.max_passes = static_cast<int>(passes);
  cut.max_tilt_rad = tilt_deg * M_PI / 180;
  cut.tilt_steps = static_cast<int>(tilt_steps);
  cut.max_roll_rad = roll_deg * M_PI / 180;
  cut.roll_steps = static_cast<int>(roll_steps);
  cut.alternatives = static_cast<int>(alternatives);
  VB_ASSIGN_OR_RETURN(cut.min_clearance_m,
                      flags.Double("cut-min-clearance-m", cut.min_clearance_m));
  plan::SecateurOptions secateur;
  VB_ASSIGN_OR_RETURN(secateur.jaw_opening_m,
                      flags.Double("jaw-opening-m", secateur.jaw_opening_m));
  if (absl::Status s = secateur.Validate(); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat("--jaw-opening-m: ", s.message()));
  if (tool == "mill_end") {
    setup.robot = plan::DefaultUr5(plan::MillEndTool());
  } else if (tool == "secateur") {
    setup.robot = plan::DefaultUr5(plan::SecateurTool(secateur));
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat("--tool: unknown tool '", tool, "' (expected secateur or mill_end)"));
  }
  if (!(acceleration > 0) || !std::isfinite(acceleration))
    return absl::InvalidArgumentError("--joint-acceleration: must be finite and > 0 (rad/s^2)");
  setup.robot.limits.max_acceleration = plan::Joints::Constant(acceleration);
  // The cameras where the stop's calibration puts them; the default rig's without one.
  if (calibration.empty()) {
    setup.platform = plan::DefaultPlatform();
  } else {
    auto rig = capture::ReadCalibrationYaml(calibration);
    if (!rig.ok())
      return absl::Status(rig.status().code(),
                          absl::StrCat("--calibration: ", rig.status().message()));
    auto platform = plan::PlatformAroundRig(*rig);
    if (!platform.ok())
      return absl::InvalidArgumentError(
          absl::StrCat("--calibration: ", calibration, ": ", platform.status().message()));
    setup.platform = *std::move(platform);
  }
  VB_ASSIGN_OR_RETURN(o.checker, ParseCheckerKind(checker));
  o.home = plan::DefaultHome();
  if (absl::Status s = o.Validate(); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat("plan flags: ", s.message()));
  return setup;
}

}  // namespace vb::app
