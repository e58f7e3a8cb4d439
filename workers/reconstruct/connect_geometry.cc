// SPDX-License-Identifier: Apache-2.0
// Connection's geometry: distances, tangents, taper and crossing evidence (connect.h,
// connect_internal.h).
#include <algorithm>
#include <cmath>

#include "workers/reconstruct/connect.h"
#include "workers/reconstruct/connect_internal.h"

namespace vb::reconstruct {
namespace connect_internal {

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

void Reverse(Polyline3* line) {
  std::reverse(line->points.begin(), line->points.end());
  std::reverse(line->radii.begin(), line->radii.end());
}

Eigen::Vector3d EndOutward(const Polyline3& line, bool last) {
  const double length = line.Length();
  const double s = std::min(0.03, length);
  const Eigen::Vector3d end = last ? line.points.back() : line.points.front();
  const Eigen::Vector3d d = end - line.PointAt(last ? length - s : s);
  const double n = d.norm();
  return n > 1e-12 ? Eigen::Vector3d(d / n) : Eigen::Vector3d::UnitZ();
}

double MeanRadius(const Polyline3& line, double from, double to) {
  const int n = std::max(2, static_cast<int>(std::ceil((to - from) / 0.005)) + 1);
  double sum = 0.0;
  for (int k = 0; k < n; ++k) sum += line.RadiusAt(from + (to - from) * k / (n - 1));
  return sum / n;
}

bool WhollyWithin(const Polyline3& cane, double centre_x, double within_m) {
  return std::all_of(cane.points.begin(), cane.points.end(), [&](const Eigen::Vector3d& p) {
    return std::abs(p.x() - centre_x) <= within_m;
  });
}

}  // namespace connect_internal

using connect_internal::kInf;
using connect_internal::DistanceToPolyline;
using connect_internal::EndOutward;
using connect_internal::MeanRadius;

double TaperTowardCentre(const Polyline3& cane, double centre_x) {
  const double length = cane.Length();
  if (!(length >= 0.03)) return 1.0;
  const double third = length / 3.0;
  const double front = MeanRadius(cane, 0.0, third);
  const double back = MeanRadius(cane, length - third, length);
  const bool front_inner = std::abs(cane.points.front().x() - centre_x) <
                           std::abs(cane.points.back().x() - centre_x);
  const double inner = front_inner ? front : back, outer = front_inner ? back : front;
  return outer > 0.0 ? inner / outer : 1.0;
}

CrossingEvidence MeasureCrossing(const Polyline3& child, bool base_is_last,
                                 const Polyline3& parent, const Eigen::Vector3d& point,
                                 const ConnectOptions& options, const GapSupportFn& gap_support) {
  CrossingEvidence e;
  if (child.points.size() < 2 || parent.points.size() < 2) return e;
  const Eigen::Vector3d base = base_is_last ? child.points.back() : child.points.front();
  const Eigen::Vector3d out = EndOutward(child, base_is_last);
  // Past the parent along the child's own line, not past the join point: a crossing child
  // passes in front of or behind the parent's axis.
  const double along = std::max(0.0, (point - base).dot(out));
  const double radius = parent.RadiusAt(parent.Project(point));
  e.miss_m = kInf;
  const int steps = 20;
  for (int k = 0; k <= steps; ++k) {
    const double t = (along + radius + options.crossing_clearance_m) * k / steps;
    e.miss_m = std::min(e.miss_m, DistanceToPolyline(base + out * t, parent, nullptr));
  }
  const Eigen::Vector3d from = base + out * (along + radius + options.crossing_clearance_m);
  const Eigen::Vector3d to = from + out * options.crossing_reach_m;
  // A stretch that ends on the parent runs along it (the child continues the parent from its
  // tip): the wood there is the parent's, not the child's going on.
  if (gap_support &&
      DistanceToPolyline(to, parent, nullptr) > radius + options.crossing_clearance_m) {
    e.past_support = gap_support(from, to);
  }
  return e;
}

}  // namespace vb::reconstruct
