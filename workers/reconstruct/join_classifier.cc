// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/join_classifier.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "Eigen/Core"
#include "workers/reconstruct/logistic.h"

namespace vb::reconstruct {
namespace {

// Unit tangent pointing out of the polyline at one end, over a chord of about `chord_m`
// (noise-robust: the ends of reconstructed canes wobble).
Eigen::Vector3d OutwardTangent(const Polyline3& line, bool at_last, double chord_m) {
  const double length = line.Length();
  const double s = std::min(chord_m, length);
  const Eigen::Vector3d end = at_last ? line.points.back() : line.points.front();
  const Eigen::Vector3d inner = line.PointAt(at_last ? length - s : s);
  const Eigen::Vector3d d = end - inner;
  const double n = d.norm();
  return n > 1e-12 ? Eigen::Vector3d(d / n) : Eigen::Vector3d::UnitZ();
}

double DistanceToLine(const Eigen::Vector3d& p, const Polyline3& line) {
  double d = 0.0;
  line.Project(p, &d);
  return d;
}

}  // namespace

JoinWeights DefaultJoinWeights() {
  // Trained by JoinClassifier.DISABLED_TrainOnSimulatedStops (join_classifier_test.cc) on the
  // candidate joins of the real pipeline, rig refinement included (MatchWithRigRefinement), on
  // rendered stops with the platform's fiducials, seeds 1000-1099, vine 1, calibration 1 px off,
  // once from the renderer's label images and once from the segmenter's output (main d2d0533's
  // pipeline): 63288 joins to a cane (2226 right) and 5160 to the trunk or head (3362 right),
  // gaps up to 15 cm; training AUC 0.957 (the previous weights 0.955 on the same joins). Used
  // with ConnectOptions::min_join_probability 0.12 (docs/reconstruction.md section 6). Retrained
  // on the rig adopted the same day (sim/rig.h), weights reach the same AUC (0.960) and do no
  // better in the bench, so these were kept.
  // The image features (17-21) are not used: the weights trained with them did not gain enough
  // (ImageJoinWeights).
  JoinWeights w;
  w.cane = {-1.0182, -0.0559, -1.5357, 0.0000, 0.0000, 0.5341, 0.5073, -0.4121, 0.4987,
            -0.6448, 0.1947, -0.1707, 1.9917, 1.7472, -0.0651, -0.4369, -1.5173,
            0.0, 0.0, 0.0, 0.0, 0.0};
  w.root = {0.1569, -0.1006, -0.1176, -0.3721, 0.3721, 0.0000, 0.3781, 0.0000, 0.0000,
            0.1190, 0.1167, 0.0000, 2.6093, -0.7673, 0.1016, 0.0254, 1.0847,
            0.0, 0.0, 0.0, 0.0, 0.0};
  const JoinWeights quadratic = DefaultQuadraticJoinModels();
  w.cane_quadratic = quadratic.cane_quadratic;
  w.root_quadratic = quadratic.root_quadratic;
  return w;
}

JoinWeights ImageJoinWeights() {
  // Trained by JoinClassifier.DISABLED_TrainOnSimulatedStops (VB_TRAIN_STOPS=100, seeds
  // 1000-1099, labels and images, main 6dd7b97's pipeline, session 18): 62833 joins to a cane
  // (2146 right), 5502 to the trunk or head (3624 right); training AUC 0.9623 (the same tool
  // without the image features 0.9590, DefaultJoinWeights 0.9591). Bench against
  // DefaultJoinWeights: docs/reconstruction.md section 6, "Image evidence for joins".
  JoinWeights w;
  w.cane = {-4.3353, -0.1365, -1.0028, 0.0000, 0.0000, 0.5918, 0.4731, -0.1076, 0.5652,
            -0.5101, 0.2909, -0.1586, 2.1806, 1.2636, -0.1646, -0.2381, -1.0754,
            0.8973, 2.0846, 0.2113, -0.0579, -1.2897};
  w.root = {-0.9621, 0.0148, -0.0020, -0.0193, 0.0193, 0.0000, 0.2610, 0.0000, 0.0000,
            0.0982, 0.1470, 0.0000, 2.7461, -0.6372, 0.0650, -0.0622, 1.5927,
            0.5225, 0.1467, -0.2386, -0.0248, 0.0000};
  return w;
}

JoinFeatures ComputeJoinFeatures(const JoinGeometry& j) {
  JoinFeatures f{};
  const Polyline3& child = *j.child;
  const double length = std::max(child.Length(), 1e-3);
  const Eigen::Vector3d base = j.base_is_last ? child.points.back() : child.points.front();
  const Eigen::Vector3d tip = j.base_is_last ? child.points.front() : child.points.back();
  const double base_radius = j.base_is_last ? child.radii.back() : child.radii.front();
  const Eigen::Vector3d outward = OutwardTangent(child, j.base_is_last, 0.03);
  const bool cane = j.target == JoinTarget::kCane && j.parent != nullptr;
  f[0] = 1.0;
  f[1] = j.gap_m / 0.02;
  f[2] = std::log1p(j.gap_m / 0.003);
  f[3] = j.target == JoinTarget::kHead ? 1.0 : 0.0;
  f[4] = j.target == JoinTarget::kTrunk ? 1.0 : 0.0;
  double s_on_parent = 0.0;
  if (j.parent != nullptr) s_on_parent = j.parent->Project(j.point);
  if (cane) {
    const Eigen::Vector3d t = j.parent->TangentAt(s_on_parent);
    f[5] = std::abs(outward.dot(t));
    const double parent_length = j.parent->Length();
    f[7] = std::min(1.0, std::min(s_on_parent, parent_length - s_on_parent) / 0.05);
    f[8] = (1.0 - f[7]) * f[5];
    f[11] = std::log(std::max(parent_length, 1e-3) / 0.1);
  }
  const Eigen::Vector3d gap = j.point - base;
  f[6] = gap.dot(outward) / std::max(gap.norm(), 0.005);
  if (j.parent != nullptr) {
    f[9] = std::log(base_radius / std::max(j.parent->RadiusAt(s_on_parent), 1e-4));
  }
  f[10] = std::log(length / 0.1);
  f[12] = ((tip - j.head_centre).norm() - (base - j.head_centre).norm()) / length;
  f[13] = std::min(j.base_to_head_m / 0.1, 5.0);
  if (j.parent != nullptr) {
    f[14] = std::min(DistanceToLine(tip, *j.parent) / 0.1, 3.0);
  } else {
    f[14] = std::min(j.base_to_head_m / 0.1 + length / 0.1, 3.0);
  }
  f[15] = (tip.z() - base.z()) / length;
  f[16] = std::min(j.point_to_head_m / 0.1, 5.0);
  if (j.images != nullptr) {
    const JoinImageEvidence& e = *j.images;
    f[17] = e.gap_all_views;
    f[18] = e.gap_best_two;
    f[19] = (1.0 - e.gap_best_two) * f[1];
    f[20] = e.junction_views;
    f[21] = cane ? e.past_support : 0.0;
  }
  for (double& v : f) {
    if (!std::isfinite(v)) v = 0.0;
  }
  return f;
}

bool UsesImageFeatures(const JoinWeights& weights) {
  for (int i = kFirstImageJoinFeature; i < kJoinFeatureCount; ++i) {
    if (weights.cane[i] != 0.0 || weights.root[i] != 0.0) return true;
  }
  return false;
}

double JoinProbability(const JoinFeatures& features, const JoinWeights& weights) {
  const bool root = features[3] != 0.0 || features[4] != 0.0;
  const QuadraticLogistic& quadratic = root ? weights.root_quadratic : weights.cane_quadratic;
  if (!quadratic.empty()) return quadratic.Probability(features);
  return LogisticProbability(features, root ? weights.root : weights.cane);
}

absl::Status JoinWeights::Validate() const {
  for (int i = 0; i < kJoinFeatureCount; ++i) {
    if (!std::isfinite(cane[i]) || !std::isfinite(root[i])) {
      return absl::InvalidArgumentError(absl::StrCat("join_weights: weight ", i, " not finite"));
    }
  }
  for (const auto& [name, model] : {std::pair{"cane_quadratic", &cane_quadratic},
                                    std::pair{"root_quadratic", &root_quadratic}}) {
    if (model->empty()) continue;
    if (absl::Status s = model->Validate(kJoinFeatureCount); !s.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("join_weights.", name, ": ", s.message()));
    }
  }
  return absl::OkStatus();
}

std::vector<int> QuadraticJoinFeatures(bool root) {
  std::vector<int> use;
  for (int k = 1; k <= 16; ++k) {
    const bool skip = k == 4 || (root ? (k == 5 || k == 7 || k == 8 || k == 11) : k == 3);
    if (!skip) use.push_back(k);
  }
  return use;
}

absl::StatusOr<JoinFeatures> TrainJoinClassifier(const std::vector<LabelledJoin>& examples,
                                                 double l2, int iterations) {
  return TrainLogistic<kJoinFeatureCount>(examples, l2, iterations, "joins", "TrainJoinClassifier");
}

}  // namespace vb::reconstruct
