// SPDX-License-Identifier: Apache-2.0
// Marginal probabilities of independent binary hypotheses (candidate matches) under pairwise
// exclusion constraints, by Gibbs sampling, and the minimum expected loss selection from them.
// After Botterill et al., "A Robot System for Pruning Grape Vines" (J. Field Robotics 2017),
// sec. 3.2.3: each candidate correspondence i is right with prior probability p_i (from a
// classifier), candidates that claim the same part of a 2D segment cannot both be right (the
// one-to-one constraint), and the correspondence kept is the one minimising expected loss,
// not the single most likely joint assignment.
// Thread-safe (pure functions).
#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/status.h"

namespace vb::reconstruct {

struct GibbsOptions {
  int burn_in_sweeps = 50;   // sweeps over all variables discarded before averaging
  int sweeps = 400;          // sweeps averaged (Rao-Blackwellised) after burn-in
  uint64_t seed = 1;         // the sampler is deterministic in the seed on every platform

  // INVALID_ARGUMENT naming the field for burn_in_sweeps < 0 or sweeps < 1.
  absl::Status Validate() const;
};

// Marginal probability that each hypothesis is true under the distribution
//   P(x) ∝ prod_i p_i^x_i (1 - p_i)^(1 - x_i)   if no two conflicting hypotheses are both true,
//          0                                     otherwise,
// estimated by Gibbs sampling from the empty assignment. `conflicts[i]` lists the hypotheses
// that exclude i (the relation is symmetrised; self-conflicts and out-of-range indices are
// ignored; `conflicts` may be shorter than `probabilities`). Probabilities are clamped to
// [0, 1] (NaN counts as 0). Each sweep updates every variable in a seeded random order; the
// estimate averages the conditional probability P(x_i = 1 | rest) over sweeps (Rao-Blackwell),
// which has lower variance than counting. Hypotheses without conflicts get exactly p_i.
// Invalid options are replaced by defaults (call Validate() to report them).
std::vector<double> GibbsMarginals(const std::vector<double>& probabilities,
                                   const std::vector<std::vector<int>>& conflicts,
                                   const GibbsOptions& options = {});

// Minimum expected loss selection: with loss 1 for each wrong hypothesis kept and `alpha` for
// each right one dropped, keeping i costs (1 - m_i) in expectation and dropping it alpha * m_i,
// so i is kept iff m_i > 1 / (1 + alpha). Returns the kept indices in increasing order.
// alpha <= 0 or NaN keeps nothing; alpha = +inf keeps every i with m_i > 0.
std::vector<int> SelectMinimumExpectedLoss(const std::vector<double>& marginals, double alpha);

}  // namespace vb::reconstruct
