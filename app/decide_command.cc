// SPDX-License-Identifier: Apache-2.0
// vinebot decide and vinebot phenomics: a vine model -> its cut plan, and its phenomics.
#include <chrono>
#include <iostream>

#include "absl/strings/str_cat.h"
#include "app/commands.h"
#include "app/decide_evaluation.h"
#include "core/cut_plan.h"
#include "core/status_macros.h"
#include "core/vine_model_json.h"
#include "workers/decide/decide.h"
#include "workers/decide/phenomics.h"

namespace vb::app {
namespace {

nlohmann::json Ids(const std::vector<CaneId>& ids) {
  nlohmann::json out = nlohmann::json::array();
  for (CaneId id : ids) out.push_back(id.value);
  return out;
}

}  // namespace

absl::Status RunDecide(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const std::string model_path, flags.RequiredString("model"));
  VB_ASSIGN_OR_RETURN(const std::string out, flags.RequiredString("out"));
  VB_ASSIGN_OR_RETURN(const std::string policy_path, flags.String("policy", ""));
  VB_ASSIGN_OR_RETURN(const std::string weights_path, flags.String("weights", ""));
  VB_ASSIGN_OR_RETURN(const double deadline_s, flags.Double("deadline-s", 5.0));
  VB_RETURN_IF_ERROR(flags.Finish());
  if (!(deadline_s > 0)) return absl::InvalidArgumentError("--deadline-s must be > 0");

  VB_ASSIGN_OR_RETURN(const PruningPolicy policy, PolicyOrDefault(policy_path));
  decide::DecideOptions options;
  VB_ASSIGN_OR_RETURN(options.weights, WeightsOrDefault(weights_path));
  VB_ASSIGN_OR_RETURN(const VineModel model, ReadVineModel(model_path));
  const auto start = std::chrono::steady_clock::now();
  auto decision = decide::Decide(model, policy, options, Deadline::In(deadline_s));
  const double decide_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!decision.ok())
    return absl::Status(decision.status().code(),
                        absl::StrCat(model_path, ": ", decision.status().message()));
  for (const std::string& note : decision->notes) std::cerr << "note: " << note << "\n";
  VB_RETURN_IF_ERROR(WriteCutPlan(out, decision->plan));
  const nlohmann::json summary = {{"out", out},
                                  {"keep", Ids(decision->plan.keep)},
                                  {"spurs", Ids(decision->plan.spurs)},
                                  {"cuts", decision->plan.cuts.size()},
                                  {"candidates", decision->stats.candidates},
                                  {"schemes_visited", decision->stats.schemes_visited},
                                  {"notes", decision->notes.size()},
                                  {"decide_s", decide_s}};
  std::cout << summary.dump() << "\n";
  return absl::OkStatus();
}

absl::Status RunPhenomics(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const std::string model_path, flags.RequiredString("model"));
  VB_ASSIGN_OR_RETURN(const std::string plan_path, flags.String("plan", ""));
  VB_ASSIGN_OR_RETURN(const std::string policy_path, flags.String("policy", ""));
  VB_ASSIGN_OR_RETURN(const std::string weights_path, flags.String("weights", ""));
  VB_RETURN_IF_ERROR(flags.Finish());
  if (!plan_path.empty() && (!policy_path.empty() || !weights_path.empty()))
    return absl::InvalidArgumentError(
        "--plan cannot be combined with --policy or --weights (they only matter when the plan is "
        "decided here)");

  VB_ASSIGN_OR_RETURN(const VineModel model, ReadVineModel(model_path));
  CutPlan plan;
  if (!plan_path.empty()) {
    VB_ASSIGN_OR_RETURN(plan, ReadCutPlan(plan_path));
  } else {
    // No plan given: decide one, so that the pruning weight and kept length are filled in.
    VB_ASSIGN_OR_RETURN(const PruningPolicy policy, PolicyOrDefault(policy_path));
    decide::DecideOptions options;
    VB_ASSIGN_OR_RETURN(options.weights, WeightsOrDefault(weights_path));
    auto decision = decide::Decide(model, policy, options, Deadline::In(5.0));
    if (!decision.ok())
      return absl::Status(decision.status().code(),
                          absl::StrCat(model_path, ": ", decision.status().message()));
    for (const std::string& note : decision->notes) std::cerr << "note: " << note << "\n";
    plan = std::move(decision->plan);
  }
  auto phenomics = decide::ComputePhenomics(model, &plan);
  if (!phenomics.ok())
    return absl::Status(phenomics.status().code(),
                        absl::StrCat(plan_path.empty() ? model_path : plan_path, ": ",
                                     phenomics.status().message()));
  nlohmann::json out = decide::PhenomicsToJson(*phenomics);
  out["plan"] = plan_path.empty() ? "decided" : plan_path;
  std::cout << out.dump(1) << "\n";
  return absl::OkStatus();
}

}  // namespace vb::app
