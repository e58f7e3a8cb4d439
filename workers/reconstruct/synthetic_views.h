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
  // Diagnosis (docs/reconstruction.md, "Where true length is lost"): > 0 breaks each cane's
  // segment wherever it passes within this many pixels beyond the two half-widths of another
  // cane's projection (a crossing, or a fork on both the parent and the child's base), as a
  // skeleton breaks its segments at junctions; the samples inside are left out of the segment but
  // still drawn. Runs of such samples longer than 30 px (a cane lying along another, which a
  // skeleton merges rather than breaks) are kept whole. 0 (the default): one unbroken segment
  // per cane.
  double break_at_crossings_px = 0.0;
  // Diagnosis, with break_at_crossings_px > 0: in those longer runs only the cane listed first in
  // the model keeps its samples (a skeleton draws one path for two canes lying along each other).
  bool merge_overlaps = false;
};

// One View2D per camera of `rig`: classes (background, foreground canes/trunk/head, wires,
// posts, painted in that order), one segment per cane (split where the cane leaves the image,
// and at crossings with break_at_crossings_px), with an end node at each end and no junctions; widths from the radii; wires and posts as
// Line2D from their end points; thick_mask = head discs plus every cane at least
// `thick_width_px` wide; centreline_distance_px from the segments.
std::vector<View2D> SyntheticViews(const VineModel& model, const RigCalibration& rig,
                                   const SyntheticViewOptions& options = {},
                                   double thick_width_px = 14.0);

// Diagnosis: for each cane of `model`, its samples every ~step_m along it (the first at its base,
// the last at its tip, evenly spaced) and whether `camera` sees each lying along another cane of
// `model`: within margin_px plus the two half-widths (canes drawn at least 1 px wide) of a visible
// sample of another cane, in a run of such samples longer than 30 px (shorter runs are crossings,
// which do not count). Samples outside the image are false.
std::vector<std::vector<bool>> LyingAlongAnother(const VineModel& model,
                                                 const CameraCalibration& camera, double step_m,
                                                 double margin_px);

}  // namespace vb::reconstruct
