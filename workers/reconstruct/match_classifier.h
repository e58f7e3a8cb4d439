// SPDX-License-Identifier: Apache-2.0
// The probability that a candidate match of 2D cane segments is right, from the attributes of its
// 3D reconstruction: a logistic model, as the classifiers of Botterill et al., "A Robot System for
// Pruning Grape Vines" (J. Field Robotics 2017), sec. 3.2.3, with weights trained on labelled
// candidates from simulated stops (TrainMatchClassifier). Pure functions; thread-safe.
#pragma once

#include <array>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geometry.h"
#include "workers/reconstruct/match_candidates.h"
#include "workers/reconstruct/polyline_fit.h"
#include "workers/reconstruct/quadratic_logistic.h"

namespace vb::reconstruct {

// Feature vector of a candidate; index 0 is the constant 1 (bias). See ComputeMatchFeatures.
inline constexpr int kMatchFeatureCount = 22;
using MatchFeatures = std::array<double, kMatchFeatureCount>;

// Weights of the logistic model: P(right) = 1 / (1 + exp(-w . features)). Two linear models: one
// for candidates that can be checked in at least one other view, one for a two-camera rig (whose
// other-view features are all 0). When `multi_view_quadratic` is not empty, it scores the
// candidates with other views instead of `multi_view` (features 1-21 and their products; since
// session 25 the default's, docs/reconstruction.md section 3, "A quadratic match classifier").
struct MatchClassifier {
  MatchFeatures multi_view{};
  MatchFeatures two_view{};
  QuadraticLogistic multi_view_quadratic;

  // The probability that a candidate with `features` is right: the two-view weights unless
  // `multi_view`, then the quadratic model if present, else the multi-view weights.
  double Probability(const MatchFeatures& features, bool multi_view) const;
  // OK if every weight is finite and the quadratic model, if any, is valid; INVALID_ARGUMENT
  // naming the weight otherwise.
  absl::Status Validate() const;
};

// The committed, trained weights (see match_classifier.cc for how they were produced): for
// candidates matched with a refined rig (the second pass of MatchWithRigRefinement, reconstruct.h).
// The multi-view candidates are scored by the quadratic model (DefaultQuadraticMatchModel).
MatchClassifier DefaultMatchClassifier();
// The committed quadratic model for multi-view candidates of the second pass
// (match_classifier_quadratic.cc says how it was trained).
QuadraticLogistic DefaultQuadraticMatchModel();
// Weights for candidates matched with the rig as calibrated, i.e. drifted (the first pass, whose
// confident pieces refine the rig): trained on such candidates.
MatchClassifier CalibratedRigMatchClassifier();

// What refining a candidate in the views outside its pair (RefineInOtherViews) does to it. A
// right match whose pair fixes depth poorly lies 1-2 cm deep, and the other view sees it offset
// across its cane: the refinement moves it onto that cane, and the other view agrees afterwards.
// A wrong one is refused (the curve cannot bring the residuals down) or stays where the other
// view shows no skeleton along it.
struct RefinementAgreement {
  bool kept = false;          // RefineInOtherViews kept a refined fit (returned > 0)
  double mean_shift_m = 0.0;  // mean distance between each hit's point before and after
  // Over the other views, the in-image-weighted mean distance of the points to a centreline
  // (ViewSupport::centreline_px, / 10 px as feature 13) before the refinement minus after it;
  // 0 when not kept.
  double centreline_gain = 0.0;
};

// Refines a copy of `fit` (FitPolyline of `candidate` with camera_a, camera_b) in `others`
// (RefineInOtherViews with `fit_options`, `other_options`) and measures the change.
// `before[i]` is others[i]'s CheckInView of the unrefined fit. Nothing is measured (all 0) when
// the sizes differ, others is empty, an other view lacks its `view`, or other_options.rounds is
// 0. Thread-safe.
RefinementAgreement MeasureRefinement(const MatchCandidate& candidate, const PolylineFit& fit,
                                      const CameraCalibration& camera_a,
                                      const CameraCalibration& camera_b,
                                      const std::vector<OtherView>& others,
                                      const std::vector<ViewSupport>& before,
                                      const PolylineFitOptions& fit_options,
                                      const OtherViewFitOptions& other_options);

// Features: 1, log(length / 0.1 m), log(0.25 + RMS reprojection error in a, px), the same in b,
// log(0.25 + max residual px), mean |log| radius ratio between the views, log(1 + turning per
// metre), min over the views of the mean |sin| epipolar angle, hit density (hits per sample
// spanned), coverage of segment_a and of segment_b (covered fraction), and from the other views
// (`others`, empty for none: all 0): fraction inside the image, and times that, foreground
// fraction, mean centreline distance / 10 px and tangent agreement; log(mean radius / 5 mm);
// from the other views again, fraction inside times the near and aligned fractions; and the
// squared offset of the piece's mean y (across the row) from the middle of `volume`, in units of
// its half-depth (canes cluster about the trellis plane; wrong matches scatter in depth); from
// `refinement` (all 0 by default: not measured): 1 if the refined fit was kept, log(1 + mean
// shift / 5 mm) if kept, and the centreline distance's gain.
MatchFeatures ComputeMatchFeatures(const MatchCandidate& candidate, const PolylineFit& fit,
                                   const std::vector<ViewSupport>& others,
                                   const WorkingVolume& volume,
                                   const RefinementAgreement& refinement = {});

// 1 / (1 + exp(-weights . features)), clamped against overflow.
double MatchProbability(const MatchFeatures& features, const MatchFeatures& weights);

struct LabelledMatch {
  MatchFeatures features{};
  bool right = false;
};

struct TrainOptions {
  double l2 = 1.0;       // ridge penalty on every weight but the bias
  int iterations = 50;   // Newton (IRLS) iterations at most
};

// Maximum a posteriori logistic regression (Newton's method with a ridge penalty).
// INVALID_ARGUMENT if `examples` is empty, holds only one label, or a non-finite feature;
// INTERNAL if the iteration diverges.
absl::StatusOr<MatchFeatures> TrainMatchClassifier(const std::vector<LabelledMatch>& examples,
                                                   const TrainOptions& options = {});

// Labels a reconstructed piece against ground truth: right iff at least `min_fraction` of its
// points lie within `tolerance_m` of one and the same polyline of `truth`.
bool IsRightMatch(const std::vector<Eigen::Vector3d>& points,
                  const std::vector<const Polyline3*>& truth, double tolerance_m = 0.01,
                  double min_fraction = 0.9);

// Distance from p to the polyline's axis (infinity for an empty polyline).
double DistanceToPolyline(const Eigen::Vector3d& p, const Polyline3& polyline);

}  // namespace vb::reconstruct
