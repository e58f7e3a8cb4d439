// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/connect.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "absl/strings/str_cat.h"

namespace vb::reconstruct {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Distance from p to the polyline's axis and the closest point on it.
double DistanceToPolyline(const Eigen::Vector3d& p, const Polyline3& line, Eigen::Vector3d* at) {
  double best = kInf;
  for (size_t i = 0; i + 1 < line.points.size(); ++i) {
    double t = 0.0;
    const double d = PointSegmentDistance(p, line.points[i], line.points[i + 1], &t);
    if (d < best) {
      best = d;
      if (at) *at = line.points[i] + t * (line.points[i + 1] - line.points[i]);
    }
  }
  return best;
}

// Signed distance from p to the surface of the union of spheres (negative inside), and the
// nearest surface point of the sphere that gives it.
double DistanceToHead(const Eigen::Vector3d& p, const HeadModel& head, Eigen::Vector3d* at) {
  double best = kInf;
  for (const Sphere& s : head.spheres) {
    const Eigen::Vector3d d = p - s.center;
    const double n = d.norm();
    const double signed_distance = n - s.radius;
    if (signed_distance < best) {
      best = signed_distance;
      if (at) *at = n > 1e-12 ? Eigen::Vector3d(s.center + d * (s.radius / n)) : p;
    }
  }
  return best;
}

struct Attachment {
  double distance = kInf;
  bool at_end = false;           // the cane's last point is its base (reverse it)
  int parent = -1;               // index into the output canes (0 = trunk); -1 none
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
};

}  // namespace

absl::Status ConnectOptions::Validate() const {
  for (auto [v, name] : {std::pair{max_attach_m, "max_attach_m"}, {sample_step_m, "sample_step_m"},
                         {inside_fraction, "inside_fraction"}}) {
    if (!std::isfinite(v) || v <= 0)
      return absl::InvalidArgumentError(absl::StrCat("connect options: ", name, " must be > 0"));
  }
  if (!std::isfinite(head_margin_m) || head_margin_m < 0 || !std::isfinite(spur_length_m) ||
      spur_length_m < 0) {
    return absl::InvalidArgumentError(
        "connect options: head_margin_m and spur_length_m must be >= 0");
  }
  return absl::OkStatus();
}

absl::StatusOr<VineModel> ConnectCanes(const std::vector<Polyline3>& input,
                                       const std::optional<Polyline3>& trunk_in,
                                       const HeadModel& head, const ConnectOptions& options,
                                       ConnectSummary* summary) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  for (size_t i = 0; i < input.size(); ++i) {
    if (absl::Status s = input[i].Validate(absl::StrCat("canes[", i, "]")); !s.ok()) return s;
  }
  if (trunk_in) {
    if (absl::Status s = trunk_in->Validate("trunk"); !s.ok()) return s;
  }
  ConnectSummary local;
  ConnectSummary& sum = summary ? *summary : local;
  sum = ConnectSummary();
  VineModel model;
  model.head = head;

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
    if (best < 0) return model;
    trunk = canes[best];
    canes.erase(canes.begin() + best);
    if (trunk->points.front().z() > trunk->points.back().z()) {
      std::reverse(trunk->points.begin(), trunk->points.end());
      std::reverse(trunk->radii.begin(), trunk->radii.end());
    }
  }
  const double trunk_radius = *std::max_element(trunk->radii.begin(), trunk->radii.end());

  // Drop canes that mostly lie inside the trunk or head: they are those structures seen again.
  // The longest of them inside the trunk, triangulated from the trunk's centre lines, is a more
  // accurate axis than the silhouettes' slab centres: it becomes the trunk, reaching the ground
  // along the silhouette trunk's base.
  std::vector<Polyline3> kept;
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
      ++sum.inside_trunk_or_head;
      size_t in_trunk = 0;
      for (const Eigen::Vector3d& p : samples)
        in_trunk += DistanceToPolyline(p, silhouette_trunk, nullptr) <= trunk_radius + 0.01;
      if (in_trunk >= options.inside_fraction * samples.size() && trunk_in &&
          cane.Length() > best_trunk_length) {
        best_trunk_length = cane.Length();
        Polyline3 axis = cane;
        if (axis.points.front().z() > axis.points.back().z()) {
          std::reverse(axis.points.begin(), axis.points.end());
          std::reverse(axis.radii.begin(), axis.radii.end());
        }
        if (silhouette_trunk.points.front().z() < axis.points.front().z() - 0.02) {
          axis.points.insert(axis.points.begin(), silhouette_trunk.points.front());
          axis.radii.insert(axis.radii.begin(), axis.radii.front());
        }
        axis.radii.assign(axis.points.size(), trunk_radius);
        trunk = axis;
      }
      continue;
    }
    kept.push_back(cane);
  }

  std::vector<Polyline3> tree = {*trunk};
  std::vector<int> parent_of = {-1};
  std::vector<Attachment> best(kept.size());
  std::vector<bool> done(kept.size(), false);

  auto consider = [&](size_t i, int target) {
    for (int end = 0; end < 2; ++end) {
      const Eigen::Vector3d& p = end == 0 ? kept[i].points.front() : kept[i].points.back();
      Eigen::Vector3d at = p;
      double d = DistanceToPolyline(p, tree[target], &at);
      if (target == 0) d -= trunk_radius;
      if (d < best[i].distance) best[i] = {d, end == 1, target, at};
    }
  };
  for (size_t i = 0; i < kept.size(); ++i) {
    consider(i, 0);
    for (int end = 0; end < 2; ++end) {
      const Eigen::Vector3d& p = end == 0 ? kept[i].points.front() : kept[i].points.back();
      Eigen::Vector3d at = p;
      const double d = DistanceToHead(p, head, &at) - options.head_margin_m;
      if (d < best[i].distance) best[i] = {std::max(d, 0.0), end == 1, 0, at};
    }
  }
  while (true) {
    int pick = -1;
    for (size_t i = 0; i < kept.size(); ++i) {
      if (done[i] || best[i].distance > options.max_attach_m) continue;
      if (pick < 0 || best[i].distance < best[pick].distance) pick = static_cast<int>(i);
    }
    if (pick < 0) break;
    done[pick] = true;
    Polyline3 cane = kept[pick];
    if (best[pick].at_end) {
      std::reverse(cane.points.begin(), cane.points.end());
      std::reverse(cane.radii.begin(), cane.radii.end());
    }
    // The base point lies on the parent (or the head surface) where the cane meets it.
    if ((cane.points.front() - best[pick].point).norm() > 1e-4) {
      cane.points.insert(cane.points.begin(), best[pick].point);
      cane.radii.insert(cane.radii.begin(), cane.radii.front());
    }
    tree.push_back(cane);
    parent_of.push_back(best[pick].parent);
    const int index = static_cast<int>(tree.size()) - 1;
    for (size_t i = 0; i < kept.size(); ++i)
      if (!done[i]) consider(i, index);
  }

  for (size_t i = 0; i < tree.size(); ++i) {
    Cane cane;
    cane.id = CaneId(static_cast<int>(i) + 1);
    cane.polyline = tree[i];
    if (i == 0) {
      cane.kind = CaneKind::kTrunk;
    } else {
      cane.parent_id = CaneId(parent_of[i] + 1);
      cane.kind = parent_of[i] == 0 && tree[i].Length() < options.spur_length_m ? CaneKind::kSpur
                                                                                : CaneKind::kCane;
    }
    model.canes.push_back(std::move(cane));
  }
  sum.attached = static_cast<int>(tree.size()) - 1;
  sum.unattached = static_cast<int>(std::count(done.begin(), done.end(), false));
  return model;
}

}  // namespace vb::reconstruct
