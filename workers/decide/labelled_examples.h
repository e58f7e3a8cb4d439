// SPDX-License-Identifier: Apache-2.0
// Labelled pruning decisions on disk: the training data of the scheme cost
// (workers/decide/scheme_learning.h). A label directory holds, for each example NAME,
//   NAME.model.json   the vine model (vinebot.vine_model.v1)
//   NAME.plan.json    the decision an expert made on it (vinebot.cut_plan.v1)
// Only the plan's policy, keep and spurs matter for learning; its cuts may be empty. This is the
// format `vinebot sim decide-labels` writes from simulated vines and the tablet's approvals and
// edits will be exported to. NAME is 1-128 characters of [A-Za-z0-9._-], not starting with '.'.
// Thread-compatible (pure functions over files; concurrent writers of one NAME race).
#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/cut_plan.h"
#include "core/vine_model.h"

namespace vb::decide {

inline constexpr char kLabelModelSuffix[] = ".model.json";
inline constexpr char kLabelPlanSuffix[] = ".plan.json";

struct LabelledExample {
  std::string name;
  VineModel model;
  CutPlan plan;  // the expert's decision
};

// INVALID_ARGUMENT naming the example if `name` is not a valid example name.
absl::Status ValidateExampleName(const std::string& name);

// Writes NAME.model.json and NAME.plan.json into `dir` (created if missing). INVALID_ARGUMENT
// for a bad name or a plan that fails CutPlan::ValidateAgainst(model); INTERNAL on I/O failure.
absl::Status WriteLabelledExample(const std::string& dir, const LabelledExample& example);

// The names of the examples in `dir`, sorted. NOT_FOUND if `dir` is not a directory;
// INVALID_ARGUMENT naming the file if a model has no plan or a plan no model.
absl::StatusOr<std::vector<std::string>> ListLabelledExamples(const std::string& dir);

// Reads one example. Errors from ReadVineModel / ReadCutPlan (prefixed with the path), and
// INVALID_ARGUMENT naming the example if the plan names canes the model does not have.
absl::StatusOr<LabelledExample> ReadLabelledExample(const std::string& dir,
                                                    const std::string& name);

}  // namespace vb::decide
