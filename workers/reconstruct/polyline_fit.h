// SPDX-License-Identifier: Apache-2.0
// Reconstruction of one candidate match (match_candidates.h) as a 3D polyline, and its check
// in the views that did not take part in the match. After Botterill et al., "A Robot System for
// Pruning Grape Vines" (J. Field Robotics 2017), sec. 3.2.3: a Levenberg-Marquardt fit of a few
// 3D control points minimising the reprojection error into both matched views. Pure functions;
// thread-safe.
#pragma once

#include <vector>

#include "Eigen/Core"
#include "core/calibration.h"
#include "workers/reconstruct/match_candidates.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct PolylineFitOptions {
  double control_spacing_m = 0.06;   // about one control point per this length
  int max_control_points = 12;       // upper bound on control points
  int max_iterations = 12;           // Levenberg-Marquardt iterations
  double smoothness_weight = 0.02;   // weight of second differences of control points (pixels)
};

struct PolylineFit {
  bool ok = false;                               // false: degenerate or non-finite
  std::vector<Eigen::Vector3d> control_points;   // ordered along segment_a
  std::vector<double> radii;                     // metres, one per control point
  std::vector<Eigen::Vector3d> points;           // fitted point of each hit
  std::vector<double> hit_radii;                 // metres, radius estimate at each hit
  double rms_a_px = 0.0;       // RMS reprojection error in view a (2D) and b (across segment_b)
  double rms_b_px = 0.0;
  double max_residual_px = 0.0;
  double length_m = 0.0;       // length of the control polygon
  double turning_rad = 0.0;    // total turning angle of the control polygon
  double width_log_ratio = 0.0;  // mean |log(radius seen in a / radius seen in b)|
};

// Fits a polyline to a candidate: initialised from the triangulated hits, then refined by
// Levenberg-Marquardt on 2D residuals in view a (hit sample points, fixed curve parameters from
// the arc length along segment_a) and 1D residuals across segment_b in view b, plus a small
// smoothness term. Residuals are in normalised coordinates scaled by fx (pixels). Candidates
// with more than 4 * max_control_points hits are fitted through an even subset of them.
PolylineFit FitPolyline(const MatchCandidate& candidate, const CameraCalibration& camera_a,
                        const CameraCalibration& camera_b, const PolylineFitOptions& options = {});

// Evidence for a reconstructed piece in another view.
struct ViewSupport {
  double in_image = 0.0;        // fraction of points projecting inside the image
  double foreground = 0.0;      // of those, fraction on foreground (1 px tolerance)
  double centreline_px = 0.0;   // of those, mean centreline_distance_px
  double tangent = 0.0;         // of those, mean |cos| between the projected tangent and the
                                // nearest skeleton piece within 6 px (0 when none)
  double near = 0.0;            // of those, fraction within 2.5 px of the centreline
  double aligned = 0.0;         // of those, fraction with a skeleton piece within 3 px whose
                                // direction agrees (|cos| > 0.95)
};

// `points` ordered along the piece. Views with no class image count as no evidence.
ViewSupport CheckInView(const std::vector<Eigen::Vector3d>& points, const View2D& view,
                        const ViewSamples& samples, const CameraCalibration& camera);

}  // namespace vb::reconstruct
