// SPDX-License-Identifier: Apache-2.0
// Joint refinement of a vine model's canes against the 2D evidence of every view (issue 3,
// step 4, second half), after Botterill et al., "A Robot System for Pruning Grape Vines"
// (J. Field Robotics 2017), sec. 3.2.4: all cane control points are optimised together with
// Ceres (Levenberg-Marquardt, sparse normal Cholesky), minimising
//   sum over points i, views v where i projects inside the image:
//       rho( (centreline_distance_px_v(project_v(p_i)) / reprojection_sd_px)^2 )
//   + sum over interior points: |D2 p_i - D2 r_i|^2 / kink_sd_m^2                   (sharp kinks)
//   + sum over segments: (|p_{i+1} - p_i| - h_cane)^2 / spacing_sd_m^2           (bunched points)
//   + sum over points no view sees: |p_i - p_i(start)|^2 / unseen_prior_sd_m^2
//   + base pins (below),
// where D2 p_i = p_{i-1} - 2 p_i + p_{i+1} and r is the cane's rest shape: its starting points
// smoothed (binomial kernel, sd ~1.2 points), so kinks that are noise are penalised but the
// cane's smooth curvature is not straightened where no view constrains it. The distance map is
// read through a bicubic interpolator (ceres::BiCubicInterpolator over ceres::Grid2D, of the
// squared distances, for sub-pixel precision) and rho is the Pseudo-Huber cost, Ceres'
// SoftLOneLoss with scale
// a = pseudo_huber_t_sd: residuals (in units of reprojection_sd_px) below a count
// quadratically, beyond it linearly, i.e. the cost turns robust at
// t = pseudo_huber_t_sd * reprojection_sd_px pixels (0.25 px with the defaults; the paper found
// t = 0.25 sd best). h_cane is the rest shape's mean point spacing, so noise in the input does
// not inflate the cane's length.
//
// Before the fit every cane is resampled at point_spacing_m (the output keeps that spacing;
// radii are resampled, not re-estimated: thickness comes from the 2D widths upstream).
// Topology is kept: a cane's base is tied to the point of its parent's polyline nearest to it at
// the start (a fixed segment and fraction of the parent, which itself moves). A base within
// attach_distance_m of its parent is pinned onto it (sd pin_sd_m); a base further away (canes
// growing from the head surface, whose parent is the trunk) keeps its initial offset from that
// point, softly (sd detached_base_sd_m). The trunk (the cane without a parent) has its base
// pinned to the ground, z = 0 (sd pin_sd_m), if it starts within ground_snap_m of it (the
// cameras do not see the ground: a trunk reconstructed from the images alone ends where they do,
// and is left there for the connect step).
//
// Before anything else, the trunk's base stretch (from its base up to trunk_unseen_keep_m below
// its first point inside at least trunk_min_views images, sampled every 5 mm) is cut off: below
// the images the trunk is a straight line guessed down to the ground (head.h), rarely within
// 10 mm of the true trunk, which bends. The cut stretch is appended to model->obstacles (a
// WoodObstacle: the planner still avoids it; phenomics and the metrics do not count it) when
// the call succeeds. The cut stays 5 cm below the lowest base of a cane hanging on the trunk
// (wood keeps the trunk it grows from), and the cut stretch's upper end follows the fitted
// trunk's base. A trunk no sample of which is seen so, or whose kept part would be under 1 cm,
// is left whole. A trunk that was cut is not pinned to the ground.
//
// Before the fit (so that a ghost near real structure is not pulled onto it) and again after it,
// a cane (never the trunk) is rejected if more than max_outside_fraction of its
// points lie outside `working_volume`, or if, over the (point, view) pairs where its points
// project inside the image, less than min_foreground_fraction land within
// foreground_tolerance_px of a foreground pixel (with at least min_visible_points such pairs).
// Rejected canes are removed together with their descendants (their bases hang on them).
//
// Thread-safe (pure function of its arguments; Ceres runs on the calling thread only).
#pragma once

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "core/calibration.h"
#include "core/deadline.h"
#include "core/vine_model.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct FitOptions {
  double point_spacing_m = 0.02;        // canes are resampled at this spacing before the fit
  double reprojection_sd_px = 1.0;      // expected sd of the 2D centreline error, pixels
  double pseudo_huber_t_sd = 0.25;      // SoftLOneLoss scale, in units of reprojection_sd_px
  double kink_sd_m = 0.002;             // sd of a second difference about the rest shape's
  double unseen_prior_sd_m = 0.05;      // sd holding points no view sees near their start
  double spacing_sd_m = 0.003;          // sd of a segment's length about the cane's spacing
  double pin_sd_m = 0.0002;             // sd of base-on-parent and trunk-base-on-ground pins
  double attach_distance_m = 0.015;     // bases nearer their parent than this are pinned onto it
  double detached_base_sd_m = 0.005;    // sd holding other bases at their offset from the parent
  double ground_snap_m = 0.1;           // a trunk base this near z = 0 is pinned to the ground
  int max_iterations = 30;              // Levenberg-Marquardt iterations at most
  double function_tolerance = 1e-5;     // relative cost change at which the fit has converged
  WorkingVolume working_volume;         // canes mostly outside it are rejected
  double max_outside_fraction = 0.5;    // reject a cane with more of its points outside
  double min_foreground_fraction = 0.5; // reject a cane with less of its projections on wood
  double foreground_tolerance_px = 1.5; // a projection this close to foreground counts as on it
  int min_visible_points = 3;           // fewer (point, view) projections in images: no verdict
  int trunk_min_views = 2;              // the trunk's base stretch fewer images see is cut (0: off)
  double trunk_unseen_keep_m = 0.20;    // ... but for this much of it next to the seen trunk

  // INVALID_ARGUMENT naming the field: non-finite or non-positive sizes and sds, fractions
  // outside [0, 1], max_iterations < 1, min_visible_points < 1, trunk_min_views < 0, a negative
  // or non-finite trunk_unseen_keep_m, an empty working volume.
  absl::Status Validate() const;
};

// How the fit ended.
enum class FitTermination {
  kConverged,       // function_tolerance reached (or nothing to fit)
  kIterationLimit,  // max_iterations used up; the model holds the last iterate
  kDeadline,        // the deadline expired during the solve; the model holds the best iterate
};

struct FitSummary {
  FitTermination termination = FitTermination::kConverged;
  int iterations = 0;
  double initial_cost = 0.0;            // Ceres cost (0.5 * sum of squared robustified residuals)
  double final_cost = 0.0;
  int canes_in = 0;
  int rejected_outside = 0;             // canes mostly outside the working volume
  int rejected_background = 0;          // canes projecting mostly onto background
  int removed_with_parent = 0;          // descendants of rejected canes, removed with them
  double trunk_unseen_m = 0.0;          // trunk length moved to the obstacles (unseen base)
  int canes_out = 0;
  double solve_time_s = 0.0;
  std::string message;                  // Ceres' one-line report
};

// Refines every cane of `model` (see above); rig.cameras[i] saw views[i]. On success the model
// holds the refined, resampled canes minus the rejected ones (head, wires and posts untouched)
// and `summary`, if given, the outcome.
// Deadline: if it expires (or is cancelled) before the solve starts, returns DEADLINE_EXCEEDED
// (CANCELLED) and leaves the model untouched. If it expires during the solve, the solve stops
// and the best iterate so far is kept, rejection runs, and the call returns OK with
// summary->termination == kDeadline; cancellation during the solve returns CANCELLED and leaves
// the model untouched.
// Errors (the model is untouched):
//  - INVALID_ARGUMENT for invalid options, an invalid rig, views.size() != rig.cameras.size(), a
//    view whose size differs from its camera's or whose maps are missing, mis-sized or hold
//    non-finite distances ("views[i]: ..."), and for a model failing VineModel::Validate() or
//    with coordinates beyond 1 km ("canes[i] (id N): ..."). Everything is checked before any of
//    it reaches Ceres, whose CHECKs would abort the process.
//  - INTERNAL if Ceres reports a failure.
// An empty model (no canes) is fine: OK, nothing changes.
absl::Status RefineModel(VineModel* model, const std::vector<View2D>& views,
                         const RigCalibration& rig, const FitOptions& options,
                         const Deadline& deadline, FitSummary* summary = nullptr);

}  // namespace vb::reconstruct
