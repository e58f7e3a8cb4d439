// SPDX-License-Identifier: Apache-2.0
// What `vinebot decide`, `phenomics`, `evaluate` and `bench reconstruct` share: the policy and
// weight files, and the cut-point metrics of a reconstruction (decide run on the ground truth
// and on the reconstruction, compared by core/cut_metrics.h).
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "core/cut_metrics.h"
#include "core/pruning_policy.h"
#include "core/vine_model.h"
#include "workers/decide/decide.h"

namespace vb::app {

// The policy in the file at `path` (ReadPruningPolicy), or the default policy if `path` is empty.
absl::StatusOr<PruningPolicy> PolicyOrDefault(const std::string& path);
// The scheme weights in the file at `path` (errors prefixed with the path), or the defaults.
absl::StatusOr<decide::SchemeWeights> WeightsOrDefault(const std::string& path);

struct DecidedCutMetrics {
  CutMetrics metrics;
  // Why no plan could be made for the reconstruction (then every truth cut counts as missed);
  // empty if one was made.
  std::string model_decide_error;
};

// Decides on `truth` and on `model` under `policy` and compares the plans. A reconstruction that
// decide rejects (an empty model, no trunk, deadline) is not an error: it misses every truth
// cut. Errors: decide failing on the ground truth (prefixed "truth: "), or EvaluateCuts' errors.
absl::StatusOr<DecidedCutMetrics> EvaluateDecidedCuts(const VineModel& model,
                                                      const VineModel& truth,
                                                      const PruningPolicy& policy,
                                                      const decide::DecideOptions& options = {});

// CutMetricsToJson, plus "model_decide_error" when there was one.
nlohmann::json DecidedCutMetricsToJson(const DecidedCutMetrics& m);

}  // namespace vb::app
