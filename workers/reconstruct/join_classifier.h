// SPDX-License-Identifier: Apache-2.0
// The probability that a reconstructed cane grows from a given point of the vine: a logistic
// model on the geometry of the join, as the trained join classifiers of Botterill et al., "A
// Robot System for Pruning Grape Vines" (J. Field Robotics 2017), sec. 3.2.2-3.2.4, which join
// cane parts bottom-up on features of lengths, widths, gaps and angles. Here the join is in 3D:
// one end of a cane (its base, if the join is right) and the nearest point on a possible parent
// (another cane, the trunk or the head). Weights are trained on simulated stops
// (TrainJoinClassifier; the tool is JoinClassifier.DISABLED_TrainOnSimulatedStops in
// join_classifier_test.cc). Pure functions; thread-safe.
#pragma once

#include <array>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geometry.h"
#include "core/vine_model.h"
#include "workers/reconstruct/quadratic_logistic.h"

namespace vb::reconstruct {

// Feature vector of a join; index 0 is the constant 1 (bias). See ComputeJoinFeatures.
inline constexpr int kJoinFeatureCount = 22;
// The first of the image-evidence features (kFirstImageJoinFeature .. kJoinFeatureCount - 1).
inline constexpr int kFirstImageJoinFeature = 17;
using JoinFeatures = std::array<double, kJoinFeatureCount>;

enum class JoinTarget { kCane, kTrunk, kHead };

// What the images show of a join, measured by the caller over the stop's views
// (MeasureJoinImages, join_images.h), so that the classifier stays free of 2D types. Each in
// [0, 1].
struct JoinImageEvidence {
  double gap_all_views = 0.0;   // the fraction of the gap (child's base to join point) that is
                                // wood in every view that sees it, seen by two (GapSupport)
  double gap_best_two = 0.0;    // per view, the fraction of the gap that is inside the image
                                // and on wood; the second largest of these (0 with < 2 views)
  double junction_views = 0.0;  // of the views in which the join point falls inside the image,
                                // the fraction with a skeleton junction near its projection
  double past_support = 0.0;    // joins to a cane: CrossingEvidence::past_support (connect.h),
                                // wood beyond the parent along the child's line (a crossing)
};

// The geometry of one join, as connect.cc measures it.
struct JoinGeometry {
  JoinTarget target = JoinTarget::kCane;
  const Polyline3* child = nullptr;   // the cane that would hang on the target
  bool base_is_last = false;          // which end of `child` is its base
  const Polyline3* parent = nullptr;  // the target cane or the trunk (null for the head)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // the join point on the target
  double gap_m = 0.0;                 // from the child's base to the target's surface, >= 0
  Eigen::Vector3d head_centre = Eigen::Vector3d::Zero();  // the head's (or trunk top's) centre
  double base_to_head_m = 0.0;        // from the child's base to the head's surface, >= 0
  double point_to_head_m = 0.0;       // from the join point to the head's surface, >= 0
  const JoinImageEvidence* images = nullptr;  // null: no images (the image features are 0)
};

// Features: 1; gap / 2 cm; log(1 + gap / 3 mm); target is the head; target is the trunk;
// |cos| of the angle between the child's base tangent and the target cane's tangent at the join
// point (0 for the trunk and head); how straight the gap continues the child backwards (cos of
// the gap direction with the child's outward base tangent, shrunk for gaps under 5 mm); how far
// the join point is inside the target cane (distance to its nearer end / 5 cm, at most 1; 0 for
// trunk and head); continuation (1 - inside) x parallel; log(child base radius / target radius
// at the point) (0 for the head); log(child length / 10 cm); log(target cane length / 10 cm)
// (0 for trunk and head); orientation: (distance of the tip from the head centre - that of the
// base) / child length; base distance to the head's surface / 10 cm (at most 5); the child's other end's
// distance to the target / 10 cm (at most 3); rise of the child (tip z - base z) / length;
// join point's distance to the head's surface / 10 cm (at most 5). Image evidence (beyond the
// paper's 2D features; all 0 when `images` is null): gap_all_views; gap_best_two; the gap's
// unsupported length (1 - gap_best_two) x gap / 2 cm; junction_views; past_support.
JoinFeatures ComputeJoinFeatures(const JoinGeometry& join);

// Weights of the logistic model: P(right) = 1 / (1 + exp(-w . features)). Joins to another
// cane and joins to the trunk or head are scored by separate models: what makes them likely
// differs (a fork leaves its parent's side; a cane from the head starts at its surface).
// Either model may instead be quadratic (QuadraticLogistic on a subset of features 1-16 and
// their products): when not empty it scores its joins in place of the linear weights (since
// session 25 the default's, docs/reconstruction.md section 6, "Quadratic join models").
struct JoinWeights {
  JoinFeatures cane{};  // the target is another cane
  JoinFeatures root{};  // the target is the trunk or head
  QuadraticLogistic cane_quadratic;
  QuadraticLogistic root_quadratic;

  // OK if every weight is finite and the quadratic models, if any, are valid; INVALID_ARGUMENT
  // naming the bad one otherwise.
  absl::Status Validate() const;
};

// The committed, trained weights (see join_classifier.cc for how they were produced), with the
// quadratic models of DefaultQuadraticJoinModels. They do not use the image features.
JoinWeights DefaultJoinWeights();
// The committed quadratic models (join_classifier_quadratic.cc says how they were trained): the
// base features of each, as QuadraticJoinFeatures lists them, in cane_quadratic and
// root_quadratic; the linear weights all 0.
JoinWeights DefaultQuadraticJoinModels();
// The base features of the quadratic join models: for joins to a cane, 1-16 but 3 and 4 (the
// target's kind, constant there); to the trunk or head, 1-16 but 4 (the trunk: 3 says which) and
// 5, 7, 8 and 11 (0 for them).
std::vector<int> QuadraticJoinFeatures(bool root);

// Weights trained with the image features (an option, off by default: no significant gain on
// the bench, docs/reconstruction.md section 6, "Image evidence for joins"). They need the
// images: without them (features 17-21 all 0) every join looks unsupported and falls below
// DefaultJoinWeights' probabilities. Set ConnectOptions::join_weights to these, with a
// JoinImageFn for ConnectCanes.
JoinWeights ImageJoinWeights();

// Whether either model gives an image feature a non-zero weight: only then does connection
// need to measure the images (connect.h, JoinImageFn).
bool UsesImageFeatures(const JoinWeights& weights);

// The probability of the join's target's model (features[3] or features[4] set: the root model):
// its quadratic model if not empty, else 1 / (1 + exp(-w . features)), clamped against overflow.
double JoinProbability(const JoinFeatures& features, const JoinWeights& weights);

struct LabelledJoin {
  JoinFeatures features{};
  bool right = false;
};

// Maximum a posteriori logistic regression (Newton's method, ridge `l2` on every weight but the
// bias). INVALID_ARGUMENT if `examples` is empty, holds only one label or a non-finite feature;
// INTERNAL if the iteration diverges.
// Trains the weights of one model (the caller splits the examples by target).
absl::StatusOr<JoinFeatures> TrainJoinClassifier(const std::vector<LabelledJoin>& examples,
                                                 double l2 = 1.0, int iterations = 50);

}  // namespace vb::reconstruct
