// SPDX-License-Identifier: Apache-2.0
// Correspondence: matches 2D cane segments across the views of one stop and reconstructs each
// match as a piece of cane in 3D. After Botterill et al., "A Robot System for Pruning Grape
// Vines" (J. Field Robotics 2017), sec. 3.2.3, adapted to simultaneous views:
//  1. candidates: for every pair of views (a, b), a < b, samples along each segment of a are
//     intersected, along their epipolar segments restricted to the working volume's depth range,
//     with b's segments; runs of crossings of one segment of b at consistent depths are candidate
//     matches (match_candidates.h). Samples whose segment runs nearly along the epipolar line
//     are skipped: that pair is ill-conditioned there, and a triangle rig always has a better one
//     (min_epipolar_sin; when the selected pieces are refined in the other views, only those
//     nearer, min_epipolar_sin_refined: the better pairs share a view, and where its skeleton
//     breaks the ill-conditioned pair is the only one left, its depth fixed by that view).
//     A run may continue across such a stretch (max_ill_conditioned_gap_samples; off by default).
//     In the second pass the views' strand halves (strand_halves.h) are searched after their
//     segments, and a candidate pairing two halves across their strands is dropped.
//  2. each candidate is triangulated and refined by a Levenberg-Marquardt fit of a 3D polyline
//     minimising reprojection error in a and b, then checked in the other views
//     (polyline_fit.h);
//     Optionally (refine_before_scoring, off) the fit is then refined in the views outside the
//     match (RefineInOtherViews) and scored on that geometry;
//  3. a trained logistic model gives each candidate's probability (match_classifier.h);
//  4. Gibbs sampling under the one-to-one constraint (candidates of the same view pair claiming
//     overlapping parts of one 2D segment exclude each other; optionally not where two canes lie
//     along each other in one view: SharedClaimOptions) gives marginal probabilities, and
//     the minimum expected loss selection keeps those above 1 / (1 + alpha) (gibbs.h);
//     optionally (context, off) candidates a little below that which continue a kept piece
//     are kept too (context_selection.h).
// Duplicate pieces of one cane from different view pairs are expected; cane assembly merges them.
// Thread-safe (pure functions).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/deadline.h"
#include "workers/reconstruct/context_selection.h"
#include "workers/reconstruct/gibbs.h"
#include "workers/reconstruct/match_candidates.h"
#include "workers/reconstruct/match_classifier.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/polyline_fit.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

// Where two canes lie along each other in one view, its skeleton has a single path for both, and
// the candidates of both canes from a view pair with that view claim the same stretch of it: the
// one-to-one constraint (CandidateConflicts) keeps only one of them there. The relaxation lets a
// conflicting pair of one view pair stand together when they look like two canes rather than a
// right match and a ghost: they share a segment on one side of the pair only (they part in the
// pair's other view), their curves lie at least `min_separation_m` apart over the shared stretch
// (closer: one cane twice), and each is supported over it by a view outside the pair (the view
// where the two part, where a ghost's wrong depth should project off the skeleton). Off by
// default: on tuning stops ghosts are about as well supported there and far more numerous than
// pairs of right candidates, so turning it on gained +0.001-0.004 recall for -0.02 to -0.04
// precision. How much of each claim is shared does not tell them apart either: nearly every
// conflict, right or wrong, has one candidate whose whole claim on the segment is shared.
// docs/reconstruction.md, section 3, "Shared claims".
struct SharedClaimOptions {
  bool enabled = false;                // off: every overlap of min_conflict_overlap_px conflicts
  double min_separation_m = 0.01;      // median 3D distance of the curves over it, at least
  double min_other_view_support = 0.5; // each one's inside x aligned fraction (CheckInView) over
                                       // the shared stretch in its best view outside the pair

  // INVALID_ARGUMENT naming the field: min_separation_m < 0 or not finite,
  // min_other_view_support outside [0, 1] or NaN.
  absl::Status Validate() const;
};

struct CorrespondenceOptions {
  WorkingVolume volume;                 // pieces must lie in it; bounds the epipolar search
  double sample_step_px = 4.0;          // spacing of samples along segments
  double min_epipolar_sin = 0.2;        // skip samples within ~12 deg of the epipolar line
  // The same for a pair when the selected pieces are refined in the other views
  // (other_views.rounds > 0) and a view outside the pair shows anything: samples are searched
  // down to this |sin| (~9 deg), since that view fixes the depth the pair leaves loose. Where
  // the two pairs with a third view both lose a stretch (its skeleton breaks there at a
  // crossing or junction), the pair without it is the only one left, and a cane laid along the
  // wires often runs within 12 deg of its epipolar lines (docs/reconstruction.md, section 3).
  // The first pass (rounds 0) keeps min_epipolar_sin, so the rig refinement is unchanged. 0.1
  // gained more recall on tuning seeds but lost precision.
  double min_epipolar_sin_refined = 0.15;
  int min_hits = 5;                     // shortest candidate, in samples
  int max_gap_samples = 3;              // samples a candidate may skip
  // Samples not searched for min_epipolar_sin that a candidate may skip on top of
  // max_gap_samples (CandidateOptions). Off: 8 gained little on tuning seeds and lost precision on
  // synthetic views (docs/reconstruction.md, section 3).
  int max_ill_conditioned_gap_samples = 0;
  PolylineFitOptions fit;               // the 3D polyline fit
  // The selected candidates' geometry refined with the views outside each match
  // (RefineInOtherViews; rounds 0: off). Their scores come from the two-view fit (unless
  // refine_before_scoring).
  OtherViewFitOptions other_views;
  // Refine every fitted candidate in the other views before it is scored, so that its other-view
  // features (CheckInView) and its piece see the refined geometry: a right match whose
  // ill-conditioned pair puts it 1-2 cm deep is otherwise scored by a third view that sees it
  // offset. Does nothing with other_views.rounds 0 (the first pass sets that). Off (only the
  // selected pieces are refined, after Gibbs sampling): on tuning seeds it raised recall but
  // lowered precision on 1200-1299 (docs/reconstruction.md, section 3, "Refining before scoring").
  // The classifier's refinement features (match_classifier.h, 19-21) are measured only with this
  // off and stay 0 with it on, while the committed second-pass weights expect them measured: with
  // it on, probabilities shift (retrain with it on before using it).
  bool refine_before_scoring = false;
  // Search the views' strand halves (View2D::strand_halves, strand_halves.h) after their
  // segments, both in the pairs and in the other views' checks, and drop a candidate pairing two
  // halves across the strands (CrossesStrands). The first pass, whose pieces refine the rig, does
  // not (reconstruct.h FirstPassOptions). Views without halves (the default: the 2D stage finds
  // none unless ReconstructOptions::strand_halves is enabled) are searched as before
  // (docs/reconstruction.md section 3, "Strand halves").
  bool strand_halves = true;
  double max_rms_px = 8.0;              // candidates fitting worse are dropped before scoring
  MatchClassifier classifier = DefaultMatchClassifier();  // candidate probabilities
  double min_probability = 0.02;        // candidates below are dropped before Gibbs sampling
  double min_conflict_overlap_px = 8.0; // overlap on a shared segment that makes a conflict
  SharedClaimOptions shared_claims;     // conflicts left out for two canes along each other
  GibbsOptions gibbs;                   // marginal probabilities
  // Cost of a missed match relative to a wrong one: keep marginal P > 1 / (1 + alpha). 5 was
  // chosen with the whole pipeline (MatchSegments.DISABLED_PipelineLoss) on rendered stops,
  // held-out seeds 1110-1117: cane recall 0.63 / precision 0.86 from label images, 0.63 / 0.86
  // from segmented images (2 gave 0.59 / 0.87 and 0.56 / 0.85; 16 gave 0.66 / 0.84): cane
  // assembly still drops most ghosts, but cannot recover missed canes. 4 since the selected
  // pieces are refined in the other views (other_views): with 5 that gained recall and
  // connectivity but lost a little precision (docs/reconstruction.md, section 3). 3.5 since the
  // classifier's refinement features (match_classifier.h) and the weights retrained with them on
  // the rig of 2026-11-22: with the committed weights 5 gained recall but lost precision. 4.5
  // since session 18 (docs section 3, "Alpha 4.5 adopted"): recall +0.006 / +0.004, precision
  // -0.004 / -0.005 on tuning seeds 1100-1199 / 1200-1299, spending the report seeds' precision
  // margin on the unmet recall and connectivity targets; the highest alpha tried whose precision
  // stays >= 0.912 on both ranges.
  double alpha = 4.5;
  // After the selection above, candidates between it and 1 / (1 + context.alpha) that continue a
  // kept piece and conflict with none (context_selection.h). Off by default
  // (docs/reconstruction.md, section 3, "Selection in context (session 18)").
  ContextSelectionOptions context;

  // INVALID_ARGUMENT naming the field for non-finite or out-of-range values (sample_step_px
  // outside [0.5, 50], min_epipolar_sin or min_epipolar_sin_refined outside [0, 1), min_hits < 2, max_gap_samples < 0,
  // max_ill_conditioned_gap_samples < 0, other_views out of range,
  // empty volume, alpha <= 0 or NaN, non-finite classifier weights, invalid gibbs,
  // shared_claims or context options (the field named as "shared_claims.min_separation_m",
  // "context.alpha", ...), context enabled with context.alpha < alpha...).
  absl::Status Validate() const;
};

// The candidate search options of one view pair (FindCandidates): min_epipolar_sin, or the lower
// of it and min_epipolar_sin_refined when other_views.rounds > 0 and
// `other_view_shows_anything` (a view outside the pair is not empty). For ScoreCandidates and
// the diagnosis tools.
CandidateOptions CandidateOptionsFor(const CorrespondenceOptions& options,
                                     bool other_view_shows_anything);

// A candidate with its fit, features and classifier probability.
struct ScoredCandidate {
  MatchCandidate candidate;
  PolylineFit fit;                    // refined in the other views when `refined`
  MatchFeatures features{};           // with the other views' evidence (when there are any)
  MatchFeatures two_view_features{};  // as if there were only views a and b
  bool multi_view = false;            // `features` used other views
  bool refined = false;               // `fit` was refined in the other views (RefineInOtherViews)
  double probability = 0.0;           // classifier output for `features`
};

// Steps 1-3: every candidate that was fitted (finite, inside the volume, RMS <= max_rms_px),
// refined in the other views if options ask (refine_before_scoring and other_views.rounds > 0),
// scored with options.classifier. Same errors as MatchSegments. For MatchSegments and for
// training the classifier.
absl::StatusOr<std::vector<ScoredCandidate>> ScoreCandidates(
    const std::vector<View2D>& views, const RigCalibration& rig,
    const CorrespondenceOptions& options, const Deadline& deadline);

// The same, leaving each view's resampled segments in *samples (replaced).
absl::StatusOr<std::vector<ScoredCandidate>> ScoreCandidates(
    const std::vector<View2D>& views, const RigCalibration& rig,
    const CorrespondenceOptions& options, const Deadline& deadline,
    std::vector<ViewSamples>* samples);

// Conflict lists of the one-to-one constraint over `candidates` (symmetric).
std::vector<std::vector<int>> CandidateConflicts(const std::vector<ScoredCandidate>& candidates,
                                                 double min_overlap_px);

// How two candidates of one view pair share a 2D segment (for the shared-claim relaxation).
struct SharedClaimPair {
  int sides = 0;                    // sides (a, b) on which they claim >= min_overlap_px of one
                                    // segment (0: they do not conflict; 2: the same segments)
  double max_share = 0.0;           // larger of the two: shared length / own claim on it
  double min_share = 0.0;           // the smaller of the two
  double separation_m = 0.0;        // the lower of the two median 3D distances from one's
                                    // points over the shared stretch to the other's polyline
  double min_shared_support = 0.0;  // lower of the two: best view outside the pair, inside x
                                    // aligned fraction (CheckInView) over the shared stretch
  double min_own_support = 0.0;     // the same over the unshared stretch (0 if < 2 points)
  double min_probability = 0.0;     // lower of the two probabilities
};
// candidates[i] and candidates[j] (valid indices) with the views, their samples (ScoreCandidates)
// and the rig they were matched with. Candidates of different view pairs share nothing (sides 0).
SharedClaimPair DescribeSharedClaim(const std::vector<ScoredCandidate>& candidates, int i, int j,
                                    const std::vector<View2D>& views,
                                    const std::vector<ViewSamples>& samples,
                                    const RigCalibration& rig, double min_overlap_px);
// Whether `options` lets the pair stand together (false when not enabled or sides != 1).
bool RelaxesConflict(const SharedClaimPair& pair, const SharedClaimOptions& options);

// CandidateConflicts without the conflicts that options.shared_claims relaxes (all of them kept
// when it is off); views, samples and rig as for DescribeSharedClaim.
std::vector<std::vector<int>> CandidateConflicts(const std::vector<ScoredCandidate>& candidates,
                                                 const CorrespondenceOptions& options,
                                                 const std::vector<View2D>& views,
                                                 const std::vector<ViewSamples>& samples,
                                                 const RigCalibration& rig);

// The selected pieces of cane, ordered by (view_a, view_b, segment_a), then as found.
// rig.cameras[i] took views[i]. Views may have no segments (no pieces come from them); a view
// whose width/height is 0 and has no class image counts as empty. A piece on a strand half names
// it as segment view.segments.size() + its index in view.strand_halves.
// INVALID_ARGUMENT: fewer than 2 views; views.size() != rig.cameras.size(); an invalid camera
// (non-finite calibration: RigCalibration::Validate); two camera centres closer than 1 cm; a
// view whose size differs from its camera's, or whose class/distance images have the wrong
// size; a segment or strand half with non-finite points or widths, or widths not one per point;
// a strand half whose steps to its sibling are not one per point or whose sibling index is out
// of range; invalid options.
// DEADLINE_EXCEEDED (or CANCELLED) once `deadline` expires.
absl::StatusOr<std::vector<Piece3D>> MatchSegments(const std::vector<View2D>& views,
                                                   const RigCalibration& rig,
                                                   const CorrespondenceOptions& options,
                                                   const Deadline& deadline);

}  // namespace vb::reconstruct
