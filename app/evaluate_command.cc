// SPDX-License-Identifier: Apache-2.0
#include <iostream>

#include "app/commands.h"
#include "app/decide_evaluation.h"
#include "core/model_metrics.h"
#include "core/status_macros.h"
#include "core/view_coverage.h"
#include "core/vine_model_json.h"
#include "workers/capture/bundle.h"

namespace vb::app {

absl::Status RunEvaluate(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const std::string model_path, flags.RequiredString("model"));
  VB_ASSIGN_OR_RETURN(const std::string truth_path, flags.RequiredString("truth"));
  VB_ASSIGN_OR_RETURN(const std::string policy_path, flags.String("policy", ""));
  // Optional calibration.yaml of the rig: adds how much of the true length its images cover.
  VB_ASSIGN_OR_RETURN(const std::string calibration_path, flags.String("calibration", ""));
  VB_RETURN_IF_ERROR(flags.Finish());
  VB_ASSIGN_OR_RETURN(const PruningPolicy policy, PolicyOrDefault(policy_path));
  VB_ASSIGN_OR_RETURN(const VineModel model, ReadVineModel(model_path));
  VB_ASSIGN_OR_RETURN(const VineModel truth, ReadVineModel(truth_path));
  VB_ASSIGN_OR_RETURN(const ReconstructionMetrics metrics, EvaluateReconstruction(model, truth));
  // Cut-point metrics: decide on both models (ARCHITECTURE.md "Accuracy metrics").
  VB_ASSIGN_OR_RETURN(const DecidedCutMetrics cuts, EvaluateDecidedCuts(model, truth, policy));
  nlohmann::json out = MetricsToJson(metrics);
  out.update(DecidedCutMetricsToJson(cuts));
  if (!calibration_path.empty()) {
    VB_ASSIGN_OR_RETURN(const RigCalibration rig, capture::ReadCalibrationYaml(calibration_path));
    VB_ASSIGN_OR_RETURN(const ViewCoverage coverage, EvaluateViewCoverage(truth, rig));
    out.update(ViewCoverageToJson(coverage));
  }
  std::cout << out.dump(1) << "\n";
  return absl::OkStatus();
}

}  // namespace vb::app
