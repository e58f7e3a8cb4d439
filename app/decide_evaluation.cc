// SPDX-License-Identifier: Apache-2.0
#include "app/decide_evaluation.h"

#include "absl/strings/str_cat.h"
#include "core/json_io.h"
#include "core/status_macros.h"

namespace vb::app {
namespace {

// One decision is milliseconds; the deadline only bounds a pathological model.
constexpr double kDecideDeadlineS = 10.0;

}  // namespace

absl::StatusOr<PruningPolicy> PolicyOrDefault(const std::string& path) {
  if (path.empty()) return PruningPolicy{};
  return ReadPruningPolicy(path);
}

absl::StatusOr<decide::SchemeWeights> WeightsOrDefault(const std::string& path) {
  if (path.empty()) return decide::DefaultSchemeWeights();
  VB_ASSIGN_OR_RETURN(const nlohmann::json json, ReadJsonFile(path));
  auto weights = decide::SchemeWeightsFromJson(json);
  if (!weights.ok())
    return absl::Status(weights.status().code(),
                        absl::StrCat(path, ": ", weights.status().message()));
  return weights;
}

absl::StatusOr<DecidedCutMetrics> EvaluateDecidedCuts(const VineModel& model,
                                                      const VineModel& truth,
                                                      const PruningPolicy& policy,
                                                      const decide::DecideOptions& options) {
  auto truth_decision = decide::Decide(truth, policy, options, Deadline::In(kDecideDeadlineS));
  if (!truth_decision.ok())
    return absl::Status(truth_decision.status().code(),
                        absl::StrCat("truth: ", truth_decision.status().message()));
  DecidedCutMetrics out;
  auto model_decision = decide::Decide(model, policy, options, Deadline::In(kDecideDeadlineS));
  if (!model_decision.ok()) out.model_decide_error = std::string(model_decision.status().message());
  VB_ASSIGN_OR_RETURN(out.metrics,
                      EvaluateCuts(truth, truth_decision->plan, model,
                                   model_decision.ok() ? &model_decision->plan : nullptr));
  return out;
}

nlohmann::json DecidedCutMetricsToJson(const DecidedCutMetrics& m) {
  nlohmann::json j = CutMetricsToJson(m.metrics);
  if (!m.model_decide_error.empty()) j["model_decide_error"] = m.model_decide_error;
  return j;
}

}  // namespace vb::app
