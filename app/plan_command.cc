// SPDX-License-Identifier: Apache-2.0
// vinebot plan: a vine model and its cut plan -> a timed arm trajectory (workers/plan).
#include <iostream>

#include "absl/strings/str_cat.h"
#include "app/commands.h"
#include "app/plan_flags.h"
#include "core/cut_plan.h"
#include "core/status_macros.h"
#include "core/trajectory.h"
#include "core/vine_model_json.h"
#include "workers/plan/plan_vine.h"

namespace vb::app {

absl::Status RunPlan(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const std::string model_path, flags.RequiredString("model"));
  VB_ASSIGN_OR_RETURN(const std::string cuts_path, flags.RequiredString("cuts"));
  VB_ASSIGN_OR_RETURN(const std::string out, flags.RequiredString("out"));
  VB_ASSIGN_OR_RETURN(const double deadline_s, flags.Double("deadline-s", 10.0));
  VB_ASSIGN_OR_RETURN(const PlanSetup setup, ParsePlanSetup(flags));
  VB_RETURN_IF_ERROR(flags.Finish());
  if (!(deadline_s > 0)) return absl::InvalidArgumentError("--deadline-s must be > 0");

  VB_ASSIGN_OR_RETURN(const VineModel model, ReadVineModel(model_path));
  VB_ASSIGN_OR_RETURN(const CutPlan plan, ReadCutPlan(cuts_path));
  if (absl::Status s = plan.ValidateAgainst(model); !s.ok())
    return absl::InvalidArgumentError(
        absl::StrCat(cuts_path, ": does not fit ", model_path, ": ", s.message()));
  auto result = plan::PlanVine(model, plan, setup.robot, setup.platform, setup.options,
                               Deadline::In(deadline_s));
  if (!result.ok())
    return absl::Status(result.status().code(),
                        absl::StrCat(model_path, ": ", result.status().message()));
  for (const std::string& note : result->stats.notes) std::cerr << "note: " << note << "\n";
  VB_RETURN_IF_ERROR(WriteTrajectory(out, result->trajectory));
  nlohmann::json unplanned = nlohmann::json::array();
  for (const UnplannedCut& u : result->trajectory.unplanned)
    unplanned.push_back({{"cut_id", u.cut_id.value}, {"reason", u.reason}});
  const plan::PlanStats& s = result->stats;
  // In this order (planned cuts first), not sorted: the line is read by people and scripts.
  const nlohmann::ordered_json summary = {
      {"cuts", s.cuts},
      {"planned", s.planned},
      {"duration_s", result->trajectory.duration_s},
      {"unplanned", unplanned},
      {"out", out},
      {"checker", std::string(plan::CheckerKindName(setup.options.checker))},
      {"plan_s", s.total_s},
      {"checks", s.checks},
      {"order_cost_s", s.order_cost_s},
      {"given_order_cost_s", s.given_order_cost_s},
      {"margin_median_m", s.margins.median_margin_m}};
  std::cout << summary.dump() << "\n";
  return absl::OkStatus();
}

}  // namespace vb::app
