// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/context_selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "absl/strings/str_cat.h"
#include "core/geometry.h"

namespace vb::reconstruct {
namespace {

absl::Status Invalid(const std::string& field, const std::string& message) {
  return absl::InvalidArgumentError(absl::StrCat("context.", field, ": ", message));
}

// Distance from p to the polyline and the unit direction of its nearest segment (zero if the
// polyline has no segment of positive length). Not connect_internal's DistanceToPolyline: the
// selection needs the segment's direction, not the nearest point, and takes bare point lists.
double NearestOnPolyline(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& line,
                         Eigen::Vector3d* direction) {
  double best = std::numeric_limits<double>::infinity();
  direction->setZero();
  for (size_t k = 0; k + 1 < line.size(); ++k) {
    const Eigen::Vector3d d = line[k + 1] - line[k];
    if (!(d.squaredNorm() > 0.0)) continue;
    const double dist = PointSegmentDistance(p, line[k], line[k + 1]);
    if (dist < best) {
      best = dist;
      *direction = d.normalized();
    }
  }
  return best;
}

// The curve's unit direction at its first (front) or last point: its first or last segment of
// positive length; zero if none.
Eigen::Vector3d EndDirection(const std::vector<Eigen::Vector3d>& curve, bool front) {
  const size_t n = curve.size();
  for (size_t k = 0; k + 1 < n; ++k) {
    const Eigen::Vector3d d = front ? curve[k + 1] - curve[k] : curve[n - 1 - k] - curve[n - 2 - k];
    if (d.squaredNorm() > 0.0) return d.normalized();
  }
  return Eigen::Vector3d::Zero();
}

// Points along the curve about every `step_m` (its vertices and evenly between them).
std::vector<Eigen::Vector3d> Densify(const std::vector<Eigen::Vector3d>& curve, double step_m) {
  std::vector<Eigen::Vector3d> out;
  if (curve.empty()) return out;
  out.push_back(curve[0]);
  for (size_t k = 0; k + 1 < curve.size(); ++k) {
    const Eigen::Vector3d d = curve[k + 1] - curve[k];
    const int steps = std::max(1, static_cast<int>(std::ceil(d.norm() / step_m)));
    for (int s = 1; s <= steps; ++s) out.push_back(curve[k] + d * (static_cast<double>(s) / steps));
  }
  return out;
}

}  // namespace

absl::Status ContextSelectionOptions::Validate() const {
  if (!(alpha > 0.0) || !std::isfinite(alpha)) {
    return Invalid("alpha", absl::StrCat("must be finite and > 0, got ", alpha));
  }
  if (!(max_gap_m > 0.0) || !std::isfinite(max_gap_m)) {
    return Invalid("max_gap_m", absl::StrCat("must be finite and > 0, got ", max_gap_m));
  }
  if (!(min_cos >= 0.0 && min_cos <= 1.0)) {
    return Invalid("min_cos", absl::StrCat("must be in [0, 1], got ", min_cos));
  }
  if (!(min_new_fraction >= 0.0 && min_new_fraction <= 1.0)) {
    return Invalid("min_new_fraction", absl::StrCat("must be in [0, 1], got ", min_new_fraction));
  }
  return absl::OkStatus();
}

std::vector<int> SelectInContext(const std::vector<std::vector<Eigen::Vector3d>>& curves,
                                 const std::vector<double>& marginals,
                                 const std::vector<std::vector<int>>& conflicts,
                                 const std::vector<int>& kept,
                                 const ContextSelectionOptions& options) {
  std::vector<int> added;
  if (!options.enabled) return added;
  const int n = static_cast<int>(std::min(curves.size(), marginals.size()));
  std::vector<bool> taken(n, false);
  for (int k : kept) {
    if (k >= 0 && k < n) taken[k] = true;
  }
  const double threshold = 1.0 / (1.0 + options.alpha);
  std::vector<int> order;
  for (int i = 0; i < n; ++i) {
    if (!taken[i] && marginals[i] > threshold && curves[i].size() >= 2) order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](int l, int r) { return marginals[l] > marginals[r]; });

  // A point's distance to the nearest kept curve, and that curve's direction there.
  auto nearest_kept = [&](const Eigen::Vector3d& p, Eigen::Vector3d* direction) {
    double best = std::numeric_limits<double>::infinity();
    for (int k : kept) {
      if (k < 0 || k >= n) continue;
      Eigen::Vector3d d;
      const double dist = NearestOnPolyline(p, curves[k], &d);
      if (dist < best) {
        best = dist;
        *direction = d;
      }
    }
    return best;
  };
  const double step_m = std::max(0.002, options.max_gap_m / 3.0);
  for (int i : order) {
    bool free = true;
    if (i < static_cast<int>(conflicts.size())) {
      for (int j : conflicts[i]) free = free && !(j >= 0 && j < n && taken[j]);
    }
    if (!free) continue;
    const std::vector<Eigen::Vector3d>& curve = curves[i];
    bool attached = false;
    for (const bool front : {true, false}) {
      Eigen::Vector3d kept_direction = Eigen::Vector3d::Zero();
      const double gap = nearest_kept(front ? curve.front() : curve.back(), &kept_direction);
      const double cos = std::abs(EndDirection(curve, front).dot(kept_direction));
      attached = attached || (gap <= options.max_gap_m && cos >= options.min_cos);
    }
    if (!attached) continue;
    const std::vector<Eigen::Vector3d> samples = Densify(curve, step_m);
    int away = 0;
    for (const Eigen::Vector3d& p : samples) {
      Eigen::Vector3d unused;
      away += nearest_kept(p, &unused) > options.max_gap_m ? 1 : 0;
    }
    if (static_cast<double>(away) < options.min_new_fraction * samples.size()) continue;
    taken[i] = true;
    added.push_back(i);
  }
  std::sort(added.begin(), added.end());
  return added;
}

}  // namespace vb::reconstruct
