// SPDX-License-Identifier: Apache-2.0
// A vine's pruning decision: the policy it was made under, the canes kept, the spurs left and the
// cuts to make (format "vinebot.cut_plan.v1", ARCHITECTURE.md "Cut plan").
// Plain value types; thread-compatible.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/ids.h"
#include "core/pruning_policy.h"
#include "core/vine_model.h"
#include "Eigen/Core"
#include "nlohmann/json.hpp"

namespace vb {

inline constexpr char kCutPlanFormat[] = "vinebot.cut_plan.v1";

enum class CutReason {
  kRemove,   // the cane goes: cut near its base
  kSpur,     // the cane is shortened to a spur
  kShorten,  // a kept cane is shortened to the policy's maximum length
};

std::string_view CutReasonName(CutReason reason);  // "remove", "spur", "shorten"
absl::StatusOr<CutReason> ParseCutReason(std::string_view name);

struct Cut {
  CutId id;
  CaneId cane_id;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();      // on the cane's axis, platform frame
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ(); // unit cane tangent at the cut, base->tip
  double diameter_m = 0.0;                              // cane diameter at the cut
  CutReason reason = CutReason::kRemove;
};

struct CutPlan {
  PruningPolicy policy;
  std::vector<CaneId> keep;
  std::vector<CaneId> spurs;
  std::vector<Cut> cuts;

  // INVALID_ARGUMENT naming the element: invalid policy, duplicate or non-positive cut ids, a
  // cane listed twice in keep or spurs or both kept and spurred, non-finite points, a direction
  // that is not unit length (to 1e-6), non-positive diameter.
  absl::Status Validate() const;
  // Validate() plus: every cane id named exists in `model`.
  absl::Status ValidateAgainst(const VineModel& model) const;
};

nlohmann::json CutPlanToJson(const CutPlan& plan);
// Parses and validates (CutPlan::Validate). INVALID_ARGUMENT naming the field on any problem,
// unknown fields included (the policy object follows PruningPolicyFromJson: missing policy fields
// keep their defaults).
absl::StatusOr<CutPlan> CutPlanFromJson(const nlohmann::json& json);
absl::Status WriteCutPlan(const std::string& path, const CutPlan& plan);
// Errors are prefixed with the path.
absl::StatusOr<CutPlan> ReadCutPlan(const std::string& path);

}  // namespace vb
