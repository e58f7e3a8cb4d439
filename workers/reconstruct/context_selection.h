// SPDX-License-Identifier: Apache-2.0
// Context-aware selection of candidate matches (beyond Botterill et al.; docs/reconstruction.md,
// section 3, "Selection in context (session 18)"). The minimum expected loss selection
// (gibbs.h) keeps a candidate when its marginal P > 1 / (1 + alpha), judging each alone. Right
// candidates of canes that lie along other canes score low (their two views disagree on width),
// while a ghost tends to float: its 3D curve, made of two different canes' images, rarely
// continues a piece that was kept. So after the normal selection a candidate between the two
// thresholds, 1 / (1 + context alpha) < P <= 1 / (1 + alpha), is also kept when
//  - it conflicts (one-to-one constraint) with no kept candidate, nor with one added before it
//    (candidates are taken by decreasing P, ties by index);
//  - one end of its curve lies within max_gap_m of a kept curve (of the normal selection; added
//    candidates do not attach others, so no chain of ghosts grows from one piece), and the
//    curve's direction at that end is within acos(min_cos) of the kept curve's there (either
//    sense): it continues the kept piece rather than crossing it;
//  - at least min_new_fraction of its length lies farther than max_gap_m from every kept curve:
//    it adds cane where none is, rather than doubling a kept piece.
// Correspondence does not know the head or trunk yet (step 5 runs after assembly), so no rule
// attaches a candidate to them. Off by default: on tuning stops 1100-1199 (context alpha 9) it
// gained +0.0023 recall for -0.0034 precision, a worse trade than raising alpha; a third of the
// length it added on 1300-1319 lay off every drawn cane (runs that go on past a parting onto
// another cane continue a kept piece by construction). Thread-safe (pure functions).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "absl/status/status.h"

namespace vb::reconstruct {

struct ContextSelectionOptions {
  bool enabled = false;             // off: the normal selection only
  double alpha = 9.0;               // lower threshold 1 / (1 + alpha); >= the selection's alpha
  double max_gap_m = 0.015;         // an end this near a kept curve attaches to it
  double min_cos = 0.9;             // |cos| of the angle between the two curves' directions there
  double min_new_fraction = 0.25;   // length farther than max_gap_m from every kept curve

  // INVALID_ARGUMENT naming the field ("context.alpha", ...): alpha not finite or <= 0,
  // max_gap_m not finite or <= 0, min_cos or min_new_fraction outside [0, 1] or NaN. That alpha
  // is at least the selection's is CorrespondenceOptions::Validate's check.
  absl::Status Validate() const;
};

// The candidates added to `kept` (the normal selection's indices into `curves`) by the rule
// above, in increasing order; empty when options are not enabled. `curves[i]` is candidate i's
// 3D polyline (a curve with fewer than 2 points neither attaches nor is added), `marginals[i]`
// its marginal probability, `conflicts[i]` the candidates it excludes (symmetric, as
// CandidateConflicts gives; may be shorter than `curves`). `marginals` has one entry per curve.
std::vector<int> SelectInContext(const std::vector<std::vector<Eigen::Vector3d>>& curves,
                                 const std::vector<double>& marginals,
                                 const std::vector<std::vector<int>>& conflicts,
                                 const std::vector<int>& kept,
                                 const ContextSelectionOptions& options);

}  // namespace vb::reconstruct
