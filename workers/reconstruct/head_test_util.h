// SPDX-License-Identifier: Apache-2.0
// Test support shared by the head tests (head_test.cc, head_reach_test.cc): a known head to carve
// and the metrics to score it by.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/calibration.h"
#include "core/deadline.h"
#include "core/model_metrics.h"
#include "core/vine_model.h"
#include "gtest/gtest.h"
#include "workers/reconstruct/head.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct::testing_util {

// The head metrics (enclosure, volume ratio) of a reconstructed head against the true one.
inline ReconstructionMetrics HeadMetrics(const HeadModel& reconstructed, const HeadModel& truth) {
  VineModel model;
  model.head = reconstructed;
  VineModel true_model;
  true_model.head = truth;
  return EvaluateReconstruction(model, true_model).value();
}

// The head carved from `views` with `options` (no depth hints, no deadline); a test failure and
// an empty head when carving fails.
inline HeadModel CarveHead(const std::vector<View2D>& views, const RigCalibration& rig,
                           const HeadOptions& options) {
  const auto head =
      ReconstructHeadAndTrunk(views, rig, WorkingVolume(), options, Deadline::Infinite());
  EXPECT_TRUE(head.ok()) << head.status();
  return head.ok() ? head->head : HeadModel();
}

// A vertical trunk of the given radius at (x, y), sampled every step_m from the ground to top_z.
inline Cane VerticalTrunk(double x, double y, double top_z, double step_m, double radius_m) {
  Cane trunk;
  trunk.id = CaneId(1);
  trunk.kind = CaneKind::kTrunk;
  for (double z = 0.0; z <= top_z + 1e-4; z += step_m) {
    trunk.polyline.points.push_back({x, y, z});
    trunk.polyline.radii.push_back(radius_m);
  }
  return trunk;
}

// A trunk 0.86 m tall at (0, 0.8) with a head of five 3 cm spheres in a row along x on its top.
inline VineModel RowOfSpheresOnATrunk() {
  VineModel vine;
  vine.canes.push_back(VerticalTrunk(0.0, 0.8, 0.86, 0.02, 0.02));
  for (double x : {-0.06, -0.03, 0.0, 0.03, 0.06})
    vine.head.spheres.push_back({{x, 0.8, 0.89}, 0.03});
  return vine;
}

// Erodes the view's thick mask by a square of (2 n + 1) px, leaving its classes (foreground) as
// they were: a head part that the thick mask's opening loses in this view alone.
inline void ErodeThickMask(int n, View2D* view) {
  const int w = view->width, h = view->height;
  for (int pass = 0; pass < 2; ++pass) {  // rows, then columns
    const std::vector<uint8_t> in = view->thick_mask;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        uint8_t v = 1;
        for (int d = -n; d <= n && v; ++d) {
          const int xx = pass == 0 ? std::clamp(x + d, 0, w - 1) : x;
          const int yy = pass == 1 ? std::clamp(y + d, 0, h - 1) : y;
          v = in[static_cast<size_t>(yy) * w + xx];
        }
        view->thick_mask[static_cast<size_t>(y) * w + x] = v;
      }
  }
}

}  // namespace vb::reconstruct::testing_util
