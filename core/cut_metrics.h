// SPDX-License-Identifier: Apache-2.0
// Cut-point accuracy (ARCHITECTURE.md "Accuracy metrics"): the cut plan decided on a
// reconstructed vine model against the cut plan decided on the ground-truth model. `vinebot
// evaluate` prints these and `vinebot bench reconstruct` averages them. Thread-safe (pure).
//
// Matching, in order:
//  1. Each reconstructed cut is assigned to the ground-truth cane (any kind, trunk included) whose
//     axis passes nearest its point. It lies on that cane, and on every other ground-truth cane
//     whose axis passes within on_cane_distance_m (10 mm, the cane recall tolerance) of its point:
//     where canes leave the head side by side a cut can be within a few millimetres of two axes,
//     and which is the nearer is then a matter of reconstruction noise. Not when the cut would
//     take wood the truth keeps on its nearest cane (step 3): then it lies on that cane only (and
//     counts as a cut on a kept cane unless it pairs there).
//  2. Ground-truth cuts and reconstructed cuts lying on the cane of the ground-truth cut pair up
//     one-to-one, greedily by increasing distance between their points, while that distance is at
//     most match_distance_m (30 mm): first the reconstructed cuts whose nearest cane it is, then
//     those that lie on it only by on_cane_distance_m, so the second rule adds pairs and never
//     takes one the nearest-cane rule makes. Each ground-truth cut has a single partner at most;
//     with one cut per cane on either side, this is "the nearest reconstructed cut on the same
//     cane".
//  3. A reconstructed cut is on a kept cane when it has no ground-truth partner, lies within
//     kept_distance_m (10 mm) of the axis of its assigned ground-truth cane or inside that cane's
//     wood (within its radius there: a thick trunk), and that cane keeps wood there in the
//     ground-truth plan: the cane is kept, spurred, or an ancestor of a kept or spurred cane (the
//     trunk always is), and the cut lies before the first ground-truth cut on that cane (if any).
//     These are the cuts that would take away wood the truth keeps (a cut on the trunk or on the
//     parent of a kept cane drops the kept cane too): the worst error.
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/cut_plan.h"
#include "core/vine_model.h"
#include "nlohmann/json.hpp"

namespace vb {

struct CutMetricsOptions {
  double match_distance_m = 0.030;  // a truth cut and a reconstructed cut match within this
  double kept_distance_m = 0.010;   // this near a kept cane's axis (or inside it) cuts it
  // A reconstructed cut lies on every true cane whose axis passes this near (besides the nearest).
  double on_cane_distance_m = 0.010;

  // INVALID_ARGUMENT naming the field unless each is positive and finite.
  absl::Status Validate() const;
};

struct CutMetrics {
  int truth_cuts = 0;
  int model_cuts = 0;
  int matched_cuts = 0;
  // Distance between matched cut points, over matched ground-truth cuts; 0 if none matched.
  double cut_error_median_m = 0.0;
  double cut_error_p95_m = 0.0;
  // Unmatched ground-truth cuts / ground-truth cuts (0 when the truth plan has no cuts).
  double cuts_missed_fraction = 0.0;
  // Unmatched reconstructed cuts / reconstructed cuts (0 when there are none).
  double cuts_spurious_fraction = 0.0;
  // Reconstructed cuts that would remove wood the ground-truth plan keeps (see above).
  int cuts_on_kept_canes = 0;
};

// The pairing behind CutMetrics, cut by cut (for diagnosis tools and tests).
struct CutMatching {
  // Per truth_plan.cuts[i]: the index of its partner in model_plan->cuts, or -1.
  std::vector<int> truth_partner;
  // Per model_plan->cuts[j]: the index of its partner in truth_plan.cuts, or -1.
  std::vector<int> model_partner;
  // Per model cut: the index into truth.canes of the cane it is assigned to (step 1), the
  // distance of its point from that cane's axis, and whether it is on a kept cane (step 3).
  std::vector<size_t> model_truth_cane;
  std::vector<double> model_truth_distance_m;
  std::vector<bool> model_on_kept_cane;
};

// The pairing of EvaluateCuts. Same errors; `model_plan` null gives no model cuts.
absl::StatusOr<CutMatching> MatchCuts(const VineModel& truth, const CutPlan& truth_plan,
                                      const VineModel& model, const CutPlan* model_plan,
                                      const CutMetricsOptions& options = {});

// Compares `model_plan` (decided on the reconstruction `model`) with `truth_plan` (decided on
// `truth`). `model_plan` null means no plan could be made for the reconstruction: every
// ground-truth cut is missed. INVALID_ARGUMENT, prefixed "truth", "truth_plan", "model" or
// "model_plan", if a model fails VineModel::Validate, a plan fails CutPlan::ValidateAgainst its
// model, or the options are invalid.
absl::StatusOr<CutMetrics> EvaluateCuts(const VineModel& truth, const CutPlan& truth_plan,
                                        const VineModel& model, const CutPlan* model_plan,
                                        const CutMetricsOptions& options = {});

// {"cut_error_median_m": ..., "cut_error_p95_m": ..., "cuts_missed_fraction": ...,
//  "cuts_spurious_fraction": ..., "cuts_on_kept_canes": ..., "truth_cuts": ..., "model_cuts": ...,
//  "matched_cuts": ...}
nlohmann::json CutMetricsToJson(const CutMetrics& metrics);

}  // namespace vb
