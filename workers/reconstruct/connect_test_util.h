// SPDX-License-Identifier: Apache-2.0
// Test support for connection (connect.h): straight canes and a one-sphere head, the scene the
// connect, head-exit and join-classifier tests build their cases in. Header-only; tests only.
#pragma once

#include "core/geometry.h"
#include "workers/reconstruct/connect.h"

namespace vb::reconstruct::connect_test {

// A straight polyline from a to b in n equal steps, every point of the given radius.
inline Polyline3 Line(Eigen::Vector3d a, Eigen::Vector3d b, double radius = 0.004, int n = 10) {
  Polyline3 line;
  for (int i = 0; i <= n; ++i) {
    line.points.push_back(a + (b - a) * (static_cast<double>(i) / n));
    line.radii.push_back(radius);
  }
  return line;
}

// The head: one sphere of 5 cm at (0, 0.8, 1.0), above a trunk along x = 0, y = 0.8.
inline HeadModel Head() {
  HeadModel head;
  head.spheres.push_back({{0, 0.8, 1.0}, 0.05});
  return head;
}

}  // namespace vb::reconstruct::connect_test
