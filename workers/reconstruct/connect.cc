// SPDX-License-Identifier: Apache-2.0
// Connection, steps 1-2 (connect.h): options, preparing the canes, finding candidate joins.
// Steps 3-6 are in connect_tree.cc, the geometry in connect_geometry.cc.
#include "workers/reconstruct/connect.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "workers/reconstruct/connect_internal.h"
#include "workers/reconstruct/join_classifier.h"

namespace vb::reconstruct {

using connect_internal::kInf;
using connect_internal::DistanceToPolyline;
using connect_internal::DistanceToHead;
using connect_internal::Reverse;

absl::Status ConnectOptions::Validate() const {
  for (auto [v, name] : {std::pair{max_attach_m, "max_attach_m"}, {sample_step_m, "sample_step_m"},
                         {inside_fraction, "inside_fraction"},
                         {max_bridge_m, "max_bridge_m"},
                         {continuation_gap_m, "continuation_gap_m"},
                         {continuation_angle_deg, "continuation_angle_deg"},
                         {crossing_reach_m, "crossing_reach_m"},
                         {crossing_clearance_m, "crossing_clearance_m"},
                         {crossing_factor, "crossing_factor"}}) {
    if (!std::isfinite(v) || v <= 0)
      return absl::InvalidArgumentError(absl::StrCat("connect options: ", name, " must be > 0"));
  }
  if (!std::isfinite(keep_within_m) || keep_within_m < 0) {
    return absl::InvalidArgumentError("connect options: keep_within_m must be >= 0");
  }
  if (!std::isfinite(keep_min_length_m) || keep_min_length_m < 0) {
    return absl::InvalidArgumentError("connect options: keep_min_length_m must be >= 0");
  }
  if (!std::isfinite(keep_taper_ratio) || keep_taper_ratio < 0 ||
      (keep_taper_ratio > 0 && keep_taper_ratio <= 1)) {
    return absl::InvalidArgumentError(
        "connect options: keep_taper_ratio must be 0 (off) or > 1 (a cane of even thickness "
        "would pass any ratio <= 1)");
  }
  if (!std::isfinite(drop_thickening_ratio) || drop_thickening_ratio < 0 ||
      (drop_thickening_ratio > 0 && drop_thickening_ratio <= 1)) {
    return absl::InvalidArgumentError(
        "connect options: drop_thickening_ratio must be 0 (off) or > 1");
  }
  if (!(crossing_factor > 0.0 && crossing_factor <= 1.0)) {
    return absl::InvalidArgumentError("connect options: crossing_factor must be in (0, 1]");
  }
  if (!std::isfinite(crossing_min_miss_m) || crossing_min_miss_m < 0) {
    return absl::InvalidArgumentError("connect options: crossing_min_miss_m must be >= 0");
  }
  if (!(crossing_min_support >= 0.0 && crossing_min_support <= 1.0)) {
    return absl::InvalidArgumentError("connect options: crossing_min_support must be in [0, 1]");
  }
  if (!(min_gap_support >= 0.0 && min_gap_support <= 1.0)) {
    return absl::InvalidArgumentError("connect options: min_gap_support must be in [0, 1]");
  }
  if (!std::isfinite(head_margin_m) || head_margin_m < 0 || !std::isfinite(spur_length_m) ||
      spur_length_m < 0) {
    return absl::InvalidArgumentError(
        "connect options: head_margin_m and spur_length_m must be >= 0");
  }
  if (!std::isfinite(head_exit_reach_m) || head_exit_reach_m < 0) {
    return absl::InvalidArgumentError("connect options: head_exit_reach_m must be >= 0");
  }
  if (!(head_exit_min_cos >= -1.0 && head_exit_min_cos <= 1.0)) {
    return absl::InvalidArgumentError("connect options: head_exit_min_cos must be in [-1, 1]");
  }
  if (!std::isfinite(head_exit_min_radius_m) || head_exit_min_radius_m < 0) {
    return absl::InvalidArgumentError(
        "connect options: head_exit_min_radius_m must be finite and >= 0");
  }
  if (!(head_exit_min_support >= 0.0 && head_exit_min_support <= 1.0)) {
    return absl::InvalidArgumentError(
        "connect options: head_exit_min_support must be in [0, 1]");
  }
  if (!std::isfinite(rescue_min_taper) || rescue_min_taper < 0) {
    return absl::InvalidArgumentError("connect options: rescue_min_taper must be finite and >= 0");
  }
  if (!(rescue_min_probability >= 0 && rescue_min_probability < 1)) {
    return absl::InvalidArgumentError(
        "connect options: rescue_min_probability must be 0 (off) or in (0, 1)");
  }
  if (!(min_join_probability > 0 && min_join_probability < 1)) {
    return absl::InvalidArgumentError("connect options: min_join_probability must be in (0, 1)");
  }
  if (rescue_min_probability > 0 && rescue_min_probability < min_join_probability) {
    return absl::InvalidArgumentError(
        "connect options: rescue_min_probability must be 0 (off) or at least "
        "min_join_probability (a rescue never takes a join less likely than none)");
  }
  if (absl::Status s = join_weights.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("connect options: ", s.message()));
  }
  return absl::OkStatus();
}

absl::StatusOr<PreparedCanes> PrepareCanes(const std::vector<Polyline3>& input,
                                           const std::optional<Polyline3>& trunk_in,
                                           const HeadModel& head, const ConnectOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  for (size_t i = 0; i < input.size(); ++i) {
    if (absl::Status s = input[i].Validate(absl::StrCat("canes[", i, "]")); !s.ok()) return s;
  }
  if (trunk_in) {
    if (absl::Status s = trunk_in->Validate("trunk"); !s.ok()) return s;
  }
  PreparedCanes out;
  std::vector<Polyline3> canes = input;
  std::optional<Polyline3> trunk = trunk_in;
  if (!trunk) {
    // No trunk from the silhouettes: the thick cane reaching lowest stands in for it.
    int best = -1;
    double best_score = kInf;
    for (size_t i = 0; i < canes.size(); ++i) {
      double low = kInf, radius = 0;
      for (size_t k = 0; k < canes[i].points.size(); ++k) {
        low = std::min(low, canes[i].points[k].z());
        radius = std::max(radius, canes[i].radii[k]);
      }
      const double score = low - 10.0 * radius;
      if (score < best_score) {
        best_score = score;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) return out;
    trunk = canes[best];
    canes.erase(canes.begin() + best);
    if (trunk->points.front().z() > trunk->points.back().z()) Reverse(&*trunk);
  }
  const double trunk_radius = *std::max_element(trunk->radii.begin(), trunk->radii.end());

  // Drop canes that mostly lie inside the trunk or head: they are those structures seen again.
  // The longest of them inside the trunk, triangulated from the trunk's centre lines, is a more
  // accurate axis than the silhouettes' slab centres: it becomes the trunk, reaching the ground
  // along the silhouette trunk's base.
  const Polyline3 silhouette_trunk = *trunk;
  double best_trunk_length = options.trunk_axis_min_fraction * silhouette_trunk.Length();
  for (const Polyline3& cane : canes) {
    const std::vector<Eigen::Vector3d> samples = cane.Sample(options.sample_step_m);
    size_t inside = 0;
    for (const Eigen::Vector3d& p : samples) {
      if (DistanceToPolyline(p, *trunk, nullptr) <= trunk_radius + 0.01 ||
          DistanceToHead(p, head, nullptr) <= 0.0) {
        ++inside;
      }
    }
    if (!samples.empty() && inside >= options.inside_fraction * samples.size()) {
      ++out.inside_trunk_or_head;
      size_t in_trunk = 0;
      for (const Eigen::Vector3d& p : samples)
        in_trunk += DistanceToPolyline(p, silhouette_trunk, nullptr) <= trunk_radius + 0.01;
      if (in_trunk >= options.inside_fraction * samples.size() && trunk_in &&
          cane.Length() > best_trunk_length) {
        best_trunk_length = cane.Length();
        Polyline3 axis = cane;
        if (axis.points.front().z() > axis.points.back().z()) Reverse(&axis);
        if (silhouette_trunk.points.front().z() < axis.points.front().z() - 0.02) {
          axis.points.insert(axis.points.begin(), silhouette_trunk.points.front());
          axis.radii.insert(axis.radii.begin(), axis.radii.front());
        }
        axis.radii.assign(axis.points.size(), trunk_radius);
        trunk = axis;
      }
      continue;
    }
    out.canes.push_back(cane);
  }
  out.trunk = trunk;
  return out;
}

std::vector<JoinCandidate> FindJoins(const PreparedCanes& prepared, const HeadModel& head,
                                     const ConnectOptions& options,
                                     const JoinImageFn& join_images) {
  std::vector<JoinCandidate> joins;
  if (!prepared.trunk) return joins;
  const Polyline3& trunk = *prepared.trunk;
  const std::vector<Polyline3>& canes = prepared.canes;
  const double trunk_radius = *std::max_element(trunk.radii.begin(), trunk.radii.end());
  // The head's centre and surface; a trunk without a head ends in its top point.
  Eigen::Vector3d centre = trunk.points.back();
  if (!head.spheres.empty()) {
    centre.setZero();
    for (const Sphere& s : head.spheres) centre += s.center;
    centre /= static_cast<double>(head.spheres.size());
  }
  auto to_head = [&](const Eigen::Vector3d& p) {
    if (head.spheres.empty()) return std::max(0.0, (p - centre).norm() - trunk_radius);
    return std::max(0.0, DistanceToHead(p, head, nullptr));
  };
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Polyline3& c : canes) {
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3d& p : c.points) box.extend(p);
    box.min().array() -= options.max_attach_m;
    box.max().array() += options.max_attach_m;
    boxes.push_back(box);
  }
  for (size_t i = 0; i < canes.size(); ++i) {
    for (int end = 0; end < 2; ++end) {
      const Eigen::Vector3d& p = end == 0 ? canes[i].points.front() : canes[i].points.back();
      JoinGeometry g;
      g.child = &canes[i];
      g.base_is_last = end == 1;
      g.head_centre = centre;
      g.base_to_head_m = to_head(p);
      auto add = [&](int parent, JoinTarget target, const Eigen::Vector3d& at, double gap) {
        if (gap > options.max_attach_m) return;
        g.target = target;
        g.parent = parent >= 0 ? &canes[parent] : (target == JoinTarget::kTrunk ? &trunk : nullptr);
        g.point = at;
        g.gap_m = std::max(0.0, gap);
        g.point_to_head_m = to_head(at);
        JoinImageEvidence evidence;
        if (join_images) {
          evidence = join_images(p, at);
          if (target == JoinTarget::kCane) {
            const GapSupportFn all_views = [&](const Eigen::Vector3d& a,
                                               const Eigen::Vector3d& b) {
              return join_images(a, b).gap_all_views;
            };
            evidence.past_support =
                MeasureCrossing(canes[i], end == 1, canes[parent], at, options, all_views)
                    .past_support;
          }
        }
        g.images = join_images ? &evidence : nullptr;  // read below, then cleared
        JoinCandidate c;
        c.child = static_cast<int>(i);
        c.base_is_last = end == 1;
        c.parent = parent;
        c.target = target;
        c.point = at;
        c.features = ComputeJoinFeatures(g);
        g.images = nullptr;  // `evidence` is this call's local
        c.probability = JoinProbability(c.features, options.join_weights);
        joins.push_back(c);
      };
      Eigen::Vector3d at = p;
      const double d_trunk = DistanceToPolyline(p, trunk, &at) - trunk_radius;
      add(-1, JoinTarget::kTrunk, at, d_trunk);
      if (!head.spheres.empty()) {
        const double d_head = DistanceToHead(p, head, &at) - options.head_margin_m;
        add(-1, JoinTarget::kHead, at, d_head);
      }
      for (size_t j = 0; j < canes.size(); ++j) {
        if (j == i || !boxes[j].contains(p)) continue;
        const double d = DistanceToPolyline(p, canes[j], &at);
        add(static_cast<int>(j), JoinTarget::kCane, at, d);
      }
    }
  }
  return joins;
}

absl::StatusOr<VineModel> ConnectCanes(const std::vector<Polyline3>& input,
                                       const std::optional<Polyline3>& trunk_in,
                                       const HeadModel& head, const ConnectOptions& options,
                                       ConnectSummary* summary,
                                       const GapSupportFn& gap_support,
                                       const JoinImageFn& join_images) {
  absl::StatusOr<PreparedCanes> prepared = PrepareCanes(input, trunk_in, head, options);
  if (!prepared.ok()) return prepared.status();
  // Measuring the images costs time: only for weights that use them.
  const JoinImageFn none;
  const JoinImageFn& images = UsesImageFeatures(options.join_weights) ? join_images : none;
  return BuildTree(*prepared, FindJoins(*prepared, head, options, images), head, options,
                   summary, gap_support);
}
}  // namespace vb::reconstruct
