// SPDX-License-Identifier: Apache-2.0
// Learning the scheme cost's weights (workers/decide/scheme.h) from labelled decisions
// (workers/decide/labelled_examples.h), so that the scheme an expert chose costs less than every
// other feasible scheme of the same vine.
//
// Formulation: a ranking of schemes with a margin, learned as a structured classifier. For
// example i with expert scheme y_i and an alternative y in its working set W_i, let
// psi = z(y) - z(y_i) (z: the scheme features divided by per-feature scales) and Delta(y_i, y)
// the loss of choosing y (SchemeLoss). The expert's scheme must cost less than every alternative
// by a margin, w . psi >= Delta, which the structural SVM (Tsochantaridis et al., "Large margin
// methods for structured and interdependent output variables", JMLR 2005) enforces with the hinge
// max_y (Delta - w . psi)+. We minimise its smooth upper bound, the softmax-margin loss (Gimpel &
// Smith, "Softmax-margin CRFs", NAACL 2010), with L2 regularisation:
//   lambda/2 |w|^2 + 1/N sum_i log(1 + sum_{y in W_i} exp(margin Delta - w . psi)),
// which is smooth and strictly convex, so Newton's method with backtracking finds its minimum
// exactly (13 unknowns). W_i starts as every feasible scheme one swap away from y_i (one kept
// cane or spur replaced by another candidate, or a kept cane and a spur trading roles); then, as
// in cutting-plane training of structural SVMs, each round runs the exact search FindBestScheme
// under the current weights on every example and adds its answer to W_i when it is not y_i.
// Rounds stop when no example adds a scheme, or after `max_rounds`.
//
// Why the defaults look extreme: a pruner's rules are close to lexicographic (a cane from the
// head beats any water shoot, whatever its length), so the weights that reproduce them differ by
// orders of magnitude and resolving the smallest differences in the data needs large weights;
// lambda only keeps them finite. A wrong kept cane costs `keep_loss` times a wrong spur in Delta,
// which pushes the kept-cane weights above the spur weights as a pruner's priorities do (kept
// canes carry next season's crop).
//
// Feature scaling: features come in metres, millimetres, radians and counts. Each feature is
// divided by the root mean square of its difference over the initial working sets (1 if that is
// zero), so the regulariser treats them alike; the returned weights are in raw feature units
// (w_raw = w_scaled / scale), ready for FindBestScheme.
//
// Deterministic: no randomness in training; the hold-out split uses a fixed seed.
// Thread-safe (pure functions).
#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/deadline.h"
#include "core/pruning_policy.h"
#include "workers/decide/labelled_examples.h"
#include "workers/decide/scheme.h"

namespace vb::decide {

// A labelled example ready for learning: its candidates under its plan's policy and the expert's
// scheme among them.
struct RankingExample {
  std::string name;
  PruningPolicy policy;
  std::vector<Candidate> candidates;
  Scheme expert;
};

// FAILED_PRECONDITION naming the example if the expert's scheme names a cane that is not a
// candidate or is not feasible (IsFeasible) under the plan's policy; such examples are reported
// and skipped by callers. Errors of FindCandidates otherwise.
absl::StatusOr<RankingExample> MakeRankingExample(const LabelledExample& example);

// Every feasible scheme one swap away from `example.expert` (see above), sorted, without
// duplicates and without the expert's scheme.
std::vector<Scheme> OneSwapNeighbours(const RankingExample& example);

// The loss of choosing `b` when `a` was right: keep_loss per cane kept in one and not the other,
// plus 1 per cane spurred in one and not the other (a kept cane and a spur trading roles:
// 2 keep_loss + 2).
double SchemeLoss(const Scheme& a, const Scheme& b, double keep_loss);

struct SchemeLearningOptions {
  double regularization = 1e-12;  // lambda, on the scaled weights (see above)
  double keep_loss = 4.0;         // Delta of a wrong kept cane, in wrong spurs
  double margin = 1.0;            // Delta is multiplied by this
  int max_rounds = 30;            // constraint-generation rounds
  int newton_iterations = 100;    // per round; each is one 13x13 linear solve

  // INVALID_ARGUMENT naming the field for a non-positive or non-finite value.
  absl::Status Validate() const;
};

struct SchemeLearningResult {
  SchemeWeights weights;                      // raw feature units, for FindBestScheme
  FeatureVector feature_scale = FeatureVector::Ones();  // z = f / scale
  int examples = 0;
  int rounds = 0;                             // rounds run
  int constraints = 0;                        // in the final working sets
  int train_agreements = 0;                   // examples whose argmin is the expert's scheme
  double train_agreement = 0.0;               // train_agreements / examples
  double objective = 0.0;                     // final objective value
};

// Learns the weights from `examples` (at least one). INVALID_ARGUMENT for bad options or no
// examples; DEADLINE_EXCEEDED / CANCELLED from `deadline`; errors of FindBestScheme.
absl::StatusOr<SchemeLearningResult> LearnSchemeWeights(
    const std::vector<RankingExample>& examples, const SchemeLearningOptions& options = {},
    const Deadline& deadline = Deadline::Infinite());

struct AgreementReport {
  int examples = 0;
  int agreements = 0;                    // the argmin scheme equals the expert's exactly
  double agreement = 0.0;                // agreements / examples (0 with no examples)
  int keep_agreements = 0;               // the kept canes alone agree
  std::vector<std::string> disagreements;  // names of examples that do not agree
};

// How often FindBestScheme under `weights` reproduces the expert's scheme (exact match of the
// kept and the spur sets). Errors of FindBestScheme and `deadline`.
absl::StatusOr<AgreementReport> MeasureAgreement(const std::vector<RankingExample>& examples,
                                                 const SchemeWeights& weights,
                                                 const Deadline& deadline = Deadline::Infinite());

// A deterministic split of `count` items: the indices of the held-out ones (round(fraction *
// count) of them, chosen by a fixed-seed permutation), sorted. fraction in [0, 1).
std::vector<size_t> HoldOutIndices(size_t count, double fraction);

}  // namespace vb::decide
