// SPDX-License-Identifier: Apache-2.0
// A wire as it hangs: a polyline along x fitted to the observed wire centres of every view
// (Line2D::centre_px), for the trellis stage (trellis3d.h). Trellis wires sag between their posts
// (a parabola, with a kink at each post: sim/trellis.h), so over the +-0.8 m a stop sees, a wire
// with a post in view can lie up to ~9 mm from the best straight line. The straight wire found by
// intersecting planes is the start: each observed centre within gate_px of its projection is
// placed along the wire where its ray passes closest to it, and the knots' y and z minimise the
// image distance of the observations from the wire (linearised about the straight wire: each
// observation is a plane through its camera centre along the wire's local image direction),
// plus a second-difference penalty that keeps the polyline smooth and extends it linearly where
// no view sees it. Observations farther than inlier_px from the fit are dropped and it is redone.
// Thread-safe (pure functions).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "core/calibration.h"
#include "Eigen/Core"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct WireFitOptions {
  double knot_spacing_m = 0.2;   // polyline knots along x, at most this far apart
  double gate_px = 10.0;         // observed centres this close to the straight wire's projection
                                 // are used
  double inlier_px = 2.5;        // after each pass, observations farther than this are dropped
  double smoothness_px = 1.0;    // weight of a knot's second difference (per px of image offset)
  double prior_px = 0.05;        // weight pulling each knot toward the straight wire (per px)
  int passes = 3;                // fits, each after dropping the previous one's outliers
  int min_observations = 30;     // fewer: no fit (the straight wire stays)

  absl::Status Validate() const;
};

// The fitted wire: knots at increasing x from a.x() to b.x(), or empty when fewer than
// min_observations centres support it. `a`, `b`: the straight wire's ends (a.x() < b.x());
// rig.cameras[i] belongs to views[i]. Lines without a centre trace stand for their straight
// extent. Preconditions: options valid, views.size() == rig.cameras.size().
std::vector<Eigen::Vector3d> FitWirePolyline(const std::vector<View2D>& views,
                                             const RigCalibration& rig, const Eigen::Vector3d& a,
                                             const Eigen::Vector3d& b,
                                             const WireFitOptions& options);

}  // namespace vb::reconstruct
