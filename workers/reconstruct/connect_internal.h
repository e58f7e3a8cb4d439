// SPDX-License-Identifier: Apache-2.0
// Geometry shared by the steps of connection (connect.cc, connect_tree.cc, connect_geometry.cc):
// not part of connect.h's contract. Pure functions; thread-safe.
#pragma once

#include <limits>

#include "core/vine_model.h"

namespace vb::reconstruct::connect_internal {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// Distance from p to the polyline's axis and the closest point on it (`at` may be null).
double DistanceToPolyline(const Eigen::Vector3d& p, const Polyline3& line, Eigen::Vector3d* at);

// Signed distance from p to the surface of the union of spheres (negative inside), and the
// nearest surface point of the sphere that gives it (`at` may be null).
double DistanceToHead(const Eigen::Vector3d& p, const HeadModel& head, Eigen::Vector3d* at);

// Reverses the points and radii of the line.
void Reverse(Polyline3* line);

// Unit tangent pointing out of the polyline at its first or last point, over ~3 cm.
Eigen::Vector3d EndOutward(const Polyline3& line, bool last);

// Mean radius over arc lengths [from, to] of the polyline, at evenly spaced samples about
// 5 mm apart (the same samples read from either end).
double MeanRadius(const Polyline3& line, double from, double to);

// Whether every point of the cane lies within `within_m` of the vine's centre along the row:
// what keeping near the vine takes as this vine's, and what dropping a far leaf does not.
bool WhollyWithin(const Polyline3& cane, double centre_x, double within_m);

}  // namespace vb::reconstruct::connect_internal
