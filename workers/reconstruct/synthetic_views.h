// SPDX-License-Identifier: Apache-2.0
// 2D views drawn directly from a known vine model, without rendering: what a perfect
// segmentation and 2D structure stage would report (no occlusion handling, no noise). Tests and
// benchmarks of the later stages (correspondence, assembly, head, wires) start from these, so a
// failure there is the later stage's own. Thread-safe (pure functions).
#pragma once

#include <vector>

#include "core/calibration.h"
#include "core/vine_model.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct SyntheticViewOptions {
  double sample_step_m = 0.004;   // spacing of 3D samples along each cane before projection
  double min_width_px = 1.0;      // canes are drawn at least this wide
  bool draw_head = true;          // head spheres as filled discs (foreground, thick)
};

// One View2D per camera of `rig`: classes (background, foreground canes/trunk/head, wires,
// posts, painted in that order), one segment per cane (split where the cane leaves the image),
// with an end node at each end and no junctions; widths from the radii; wires and posts as
// Line2D from their end points; thick_mask = head discs plus every cane at least
// `thick_width_px` wide; centreline_distance_px from the segments.
std::vector<View2D> SyntheticViews(const VineModel& model, const RigCalibration& rig,
                                   const SyntheticViewOptions& options = {},
                                   double thick_width_px = 14.0);

}  // namespace vb::reconstruct
