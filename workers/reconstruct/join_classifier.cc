// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/join_classifier.h"

#include <algorithm>
#include <cmath>
#include <string>

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
  // rendered stops, seeds 1000-1099, vine 1, calibration 1 px off, once from the renderer's label
  // images and once from the segmenter's output, the default rig since 2026-11-22 (sim/rig.h):
  // 64151 joins to a cane (2312 right) and 5472 to the trunk or head (3602 right), gaps up to
  // 15 cm; training AUC 0.957 (the weights before, trained on the old rig: 0.956).
  JoinWeights w;
  w.cane = {-1.4083, -0.0842, -1.4277, 0.0000, 0.0000, 1.0544, 0.6892, -0.6722, 0.0497,
            -0.6116, 0.1984, -0.0807, 2.0749, 1.7590, -0.0868, -0.3779, -1.5914};
  w.root = {0.1559, -0.0357, -0.1283, -0.3345, 0.3345, 0.0000, 0.4247, 0.0000, 0.0000,
            0.2657, 0.1414, 0.0000, 2.5095, -0.9737, 0.1256, -0.0280, 1.4525};
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
  for (double& v : f) {
    if (!std::isfinite(v)) v = 0.0;
  }
  return f;
}

double JoinProbability(const JoinFeatures& features, const JoinWeights& weights) {
  return LogisticProbability(features, features[3] != 0.0 || features[4] != 0.0 ? weights.root
                                                                                : weights.cane);
}

absl::StatusOr<JoinFeatures> TrainJoinClassifier(const std::vector<LabelledJoin>& examples,
                                                 double l2, int iterations) {
  return TrainLogistic<kJoinFeatureCount>(examples, l2, iterations, "joins", "TrainJoinClassifier");
}

}  // namespace vb::reconstruct
