// SPDX-License-Identifier: Apache-2.0
// Geometric primitives of the vine world, in metres. Plain value types; thread-compatible.
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "Eigen/Core"
#include "Eigen/Geometry"

namespace vb {

// A 3D polyline with a radius at every point (a cane, trunk or spur), ordered base to tip.
struct Polyline3 {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> radii;  // one per point, metres

  // OK if there are >= 2 points, one radius per point, all finite, radii > 0.
  // Errors name the offending index, prefixed by `what` (e.g. "canes[3]").
  absl::Status Validate(const std::string& what) const;

  double Length() const;
  // Cumulative arc length at each point (first is 0).
  std::vector<double> ArcLengths() const;
  // Point and radius at arc length s (clamped to [0, Length()]).
  Eigen::Vector3d PointAt(double s) const;
  double RadiusAt(double s) const;
  // The same, given `arc` = ArcLengths() of this polyline, unchanged since (the forms above compute
  // it at every call; another vector is undefined behaviour): the same values bit for bit, for
  // callers that locate many points on one polyline.
  Eigen::Vector3d PointAt(double s, const std::vector<double>& arc) const;
  double RadiusAt(double s, const std::vector<double>& arc) const;
  // Unit tangent at arc length s (direction base -> tip); the second form takes `arc` as
  // PointAt's does.
  Eigen::Vector3d TangentAt(double s) const;
  Eigen::Vector3d TangentAt(double s, const std::vector<double>& arc) const;
  // Mean diameter over the first `span_m` of the polyline (all of it if shorter): how a pruner
  // reads a cane's thickness, along a hand-width rather than at one knot. 2 * radii.front() if
  // span_m <= 0.
  double MeanBaseDiameter(double span_m) const;
  // Arc length of the point of the polyline nearest to p (ties: the nearest to the base);
  // `distance_m` (optional) receives the distance. 0 for an empty polyline.
  double Project(const Eigen::Vector3d& p, double* distance_m = nullptr) const;
  // Truncates the polyline at arc length s (keeps [0, s]). s is clamped.
  void TruncateAt(double s);
  // Resamples at roughly `step_m` spacing, keeping both ends.
  std::vector<Eigen::Vector3d> Sample(double step_m) const;
  // The polyline resampled at max(2, round(Length() / step_m) + 1) points equally spaced in arc
  // length, ends kept, radii interpolated. Precondition: step_m > 0.
  Polyline3 Resampled(double step_m) const;
};

// Line segment with a radius: the swept sphere used for canes, wires and arm links.
struct Capsule {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

struct Sphere {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

// Closest distance between point p and segment [a, b]; `t` (optional) receives the
// segment parameter in [0, 1] of the closest point.
double PointSegmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                            const Eigen::Vector3d& b, double* t = nullptr);

// Closest distance between segments [p0, p1] and [q0, q1].
double SegmentSegmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                              const Eigen::Vector3d& q0, const Eigen::Vector3d& q1);

// True if every entry of `m` is finite.
template <typename Derived>
bool AllFinite(const Eigen::MatrixBase<Derived>& m) {
  return m.allFinite();
}

}  // namespace vb
