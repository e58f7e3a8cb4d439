// SPDX-License-Identifier: Apache-2.0
// Test support shared by the reconstruct tests that grow, sweep or refit synthetic canes
// (grow_test.cc, grow_refit_test.cc, depth_sweep_test.cc, depth_sweep_check_test.cc).
#pragma once

#include <vector>

#include "core/calibration.h"
#include "core/geometry.h"
#include "core/vine_model.h"
#include "workers/reconstruct/synthetic_views.h"

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

// Views drawn from `lines` alone (no head; the first line is the trunk, the others its canes; the
// drawing depends on their radii, not their kinds): nothing is thick unless a line is that wide.
inline std::vector<View2D> ViewsOf(const std::vector<Polyline3>& lines,
                                   const RigCalibration& rig) {
  VineModel model;
  for (size_t i = 0; i < lines.size(); ++i) {
    Cane cane;
    cane.id = CaneId(static_cast<int>(i) + 1);
    cane.kind = i == 0 ? CaneKind::kTrunk : CaneKind::kCane;
    if (i > 0) cane.parent_id = CaneId(1);
    cane.polyline = lines[i];
    model.canes.push_back(cane);
  }
  SyntheticViewOptions options;
  options.draw_head = false;
  return SyntheticViews(model, rig, options, 40.0);
}

inline std::vector<View2D> ViewsOf(const Polyline3& line, const RigCalibration& rig) {
  return ViewsOf(std::vector<Polyline3>{line}, rig);
}

}  // namespace vb::reconstruct::testing_util
