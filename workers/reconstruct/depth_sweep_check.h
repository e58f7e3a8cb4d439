// SPDX-License-Identifier: Apache-2.0
// What the views say about a cane the depth sweep (depth_sweep.h) would add, beyond the skeleton
// distances the sweep itself uses (docs/reconstruction.md section 4e, "A check on what the sweep
// adds (s20)"). A ghost (a smooth 3D curve 1-2 cm off the wood that finds support in the dense
// skeleton of every view) agrees with each view's skeleton within 1-1.5 px; these measures look at
// what the skeleton distance does not: the cross-section's width in every view, the direction of
// the skeleton under its projection, and its shape and position in 3D. Pure functions;
// thread-safe.
#pragma once

#include <vector>

#include "core/calibration.h"
#include "core/geometry.h"
#include "workers/reconstruct/match_candidates.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

// Measures of one run (a polyline with its radius), over the views in which it projects. Every
// "median" here is the upper median: the element at index n / 2 of the sorted values, so with an
// even count the larger of the middle two (the limits were chosen with it).
struct SweptRunFeatures {
  int views = 0;               // views in which at least half of its points project inside
  // Per point, each view's foreground width across the projected run (ForegroundWidthAcross)
  // gives the radius that view implies at the point's depth (width / 2 * depth / fx); the
  // median over points of max - min of their logs over the views (0 with fewer than two).
  double width_log_spread = 0.0;
  // Max over the views of |median over points of log(measured width / projected width)|: how far
  // the width the run's radius projects to is from what the view shows.
  double width_log_excess = 0.0;
  double foreground = 1.0;     // min over views: fraction of points whose centre and both
                               // cross-section edges (at 0.7 of the radius) lie on foreground
  double tangent = 1.0;        // min over views: mean |cos| of the projected tangent and the
                               // nearest skeleton piece within 3 px (0 where none)
  double turning_per_m = 0.0;  // total turning of the run resampled every 1.5 cm, per metre
  double straightness = 1.0;   // chord / length
  double mean_y_m = 0.0;       // mean platform y (across the row) of its points
};

// The foreground width (px) across a line through uv with unit direction `along` (pixels): from
// the foreground pixel nearest uv along the normal (within 2 px; 0 if none), walked both ways in
// half-pixel steps until background (or another class), at most max_half_px each way.
double ForegroundWidthAcross(const View2D& view, const Eigen::Vector2d& uv,
                             const Eigen::Vector2d& along, double max_half_px = 20.0);

// The features of `run` (points ordered along it, radii > 0) in `views` seen by rig.cameras
// (same count), `samples[i]` built from views[i] with rig.cameras[i] (ViewSamples). A view without
// a class image (View2D::classes of another size) is left out, as a view the run does not reach.
// Fewer than 2 points, zero length or radii not one per point: the defaults above.
SweptRunFeatures MeasureSweptRun(const Polyline3& run, const std::vector<View2D>& views,
                                 const RigCalibration& rig,
                                 const std::vector<ViewSamples>& samples);

}  // namespace vb::reconstruct
