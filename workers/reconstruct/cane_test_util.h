// SPDX-License-Identifier: Apache-2.0
// Test support shared by the reconstruct tests that grow, sweep or refit synthetic canes
// (grow_test.cc, grow_refit_test.cc, depth_sweep_test.cc).
#pragma once

#include "core/geometry.h"

namespace vb::reconstruct::testing_util {

// A smooth cane of radius 4 mm near the vine plane (y ~ 0.8 m), in front of all three cameras of
// the default rig, from x0 to x1 along the row, every 1 cm: it rises with `slope` and bends
// down (-0.1 u^2) and out of the plane (+bend_out u^2, u = x - x0).
inline Polyline3 CurvedCane(double x0, double x1, double z0, double slope,
                            double bend_out = 0.04) {
  Polyline3 line;
  for (double x = x0; x <= x1 + 1e-9; x += 0.01) {
    const double u = x - x0;
    line.points.emplace_back(x, 0.8 + bend_out * u * u, z0 + slope * u - 0.1 * u * u);
    line.radii.push_back(0.004);
  }
  return line;
}

}  // namespace vb::reconstruct::testing_util
