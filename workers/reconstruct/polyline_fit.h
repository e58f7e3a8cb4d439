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
  // Two canes lying along each other: one view sees them overlap (one cane wide), another side by
  // side (about twice as wide). Where the log of the two views' radius ratio at a hit lies within
  // 0.35 log(factor) of log(factor), the hit is read as such a bundle and its width disagreement
  // (width_log_ratio) shrinks linearly to 0 at the factor itself. Values <= 1 turn it off (the
  // default: with 2 it traded precision for recall, docs/reconstruction.md "The two reports
  // crossed").
  double bundle_width_ratio = 1.0;
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
  double width_log_ratio = 0.0;  // mean |log(radius seen in a / radius seen in b)| (see
                                 // PolylineFitOptions::bundle_width_ratio)
};

// Fits a polyline to a candidate: initialised from the triangulated hits, then refined by
// Levenberg-Marquardt on 2D residuals in view a (hit sample points, fixed curve parameters from
// the arc length along segment_a) and 1D residuals across segment_b in view b, plus a small
// smoothness term. Residuals are in normalised coordinates scaled by fx (pixels). Candidates
// with more than 4 * max_control_points hits are fitted through an even subset of them.
PolylineFit FitPolyline(const MatchCandidate& candidate, const CameraCalibration& camera_a,
                        const CameraCalibration& camera_b, const PolylineFitOptions& options = {});

// A view that took no part in a match: its resampled segments, its camera and, for callers that
// also check the fit in it (CheckInView), the view itself (not owned; RefineInOtherViews reads
// only samples and camera).
struct OtherView {
  const ViewSamples* samples = nullptr;
  const CameraCalibration* camera = nullptr;
  const View2D* view = nullptr;
};

struct OtherViewFitOptions {
  double gate_px = 2.5;       // a skeleton piece this near the projected fit is associated
  double min_cos = 0.95;      // ... if its direction agrees this well (|cos|)
  int rounds = 2;             // association + Levenberg-Marquardt rounds
  int min_associations = 3;   // fewer associated hits: the fit is left as it is
  // The refined fit is kept only if the two views' RMS residual grew by at most this and the
  // other views' RMS is at most this + 1 px (0: always kept).
  double max_residual_growth_px = 0.5;
};

// Refines a fit (FitPolyline of the same candidate and cameras) with the views that took no
// part in the match: each used hit's point is associated with the nearest skeleton piece of each
// other view within gate_px whose direction agrees, and 1D residuals across those pieces join
// the two views' residuals in a Levenberg-Marquardt fit from the current control points. A
// pair nearly along the cane's epipolar lines fixes depth poorly (a 1 px skeleton error is
// 1-2 cm at 0.8 m with the default rig), and a third view fixes it. Updates control_points and
// points only: the attributes (residuals, length, radii, ...) stay those of the two-view fit,
// from which the candidate was scored. A round that associates fewer than min_associations
// ends the rounds: the previous round's associations and fit are kept and judged (round 0:
// nothing changes). Returns the associations of the last round kept (0: the fit
// is unchanged: no other view, too few associations, a non-finite result, or residuals beyond
// max_residual_growth_px). Options are not validated here (CorrespondenceOptions::Validate).
int RefineInOtherViews(const MatchCandidate& candidate, const CameraCalibration& camera_a,
                       const CameraCalibration& camera_b, const std::vector<OtherView>& others,
                       const PolylineFitOptions& options, const OtherViewFitOptions& other_options,
                       PolylineFit* fit);

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
