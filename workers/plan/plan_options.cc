// SPDX-License-Identifier: Apache-2.0
// PlanVine's options and its checker kinds (declared in plan_vine.h).
#include "workers/plan/plan_vine.h"

#include <cmath>
#include <memory>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"

namespace vb::plan {

std::string_view CheckerKindName(CheckerKind kind) {
  switch (kind) {
    case CheckerKind::kPrimitives:
      return "primitives";
    case CheckerKind::kFclPrimitives:
      return "fcl_primitives";
    case CheckerKind::kFclMesh:
      return "fcl_mesh";
  }
  return "primitives";
}

std::unique_ptr<CollisionChecker> MakeChecker(CheckerKind kind, const RobotModel& robot,
                                              const CollisionScene& scene) {
  switch (kind) {
    case CheckerKind::kPrimitives:
      return MakePrimitiveChecker(robot, scene);
    case CheckerKind::kFclPrimitives:
      return MakeFclChecker(robot, scene, FclMode::kPrimitives);
    case CheckerKind::kFclMesh:
      return MakeFclChecker(robot, scene, FclMode::kMesh);
  }
  return MakePrimitiveChecker(robot, scene);
}

absl::Status PlanOptions::Validate() const {
  auto prefixed = [](const char* what, const absl::Status& status) {
    return status.ok() ? status
                       : absl::Status(status.code(), absl::StrCat("options.", what, ": ",
                                                                  status.message()));
  };
  VB_RETURN_IF_ERROR(prefixed("scene", scene.Validate()));
  VB_RETURN_IF_ERROR(prefixed("cut_motion", cut_motion.Validate()));
  VB_RETURN_IF_ERROR(prefixed("margins", margins.Validate()));
  VB_RETURN_IF_ERROR(prefixed("path", path.Validate()));
  if (!std::isfinite(last_resort_max_slide_m) || last_resort_max_slide_m < 0)
    return absl::InvalidArgumentError("options.last_resort_max_slide_m must be finite and >= 0");
  if (!home.allFinite()) return absl::InvalidArgumentError("options.home: non-finite joint angle");
  if (!(cut_speed_fraction > 0) || !(cut_speed_fraction <= 1))
    return absl::InvalidArgumentError("options.cut_speed_fraction must be in (0, 1]");
  if (!(sample_dt_s > 0) || !std::isfinite(sample_dt_s))
    return absl::InvalidArgumentError("options.sample_dt_s must be finite and > 0");
  if (!(cut_feed_margin_m >= 0) || !std::isfinite(cut_feed_margin_m))
    return absl::InvalidArgumentError("options.cut_feed_margin_m must be finite and >= 0");
  VB_RETURN_IF_ERROR(prefixed("blend", blend.Validate()));
  return absl::OkStatus();
}

}  // namespace vb::plan
