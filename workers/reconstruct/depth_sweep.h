// SPDX-License-Identifier: Apache-2.0
// A depth sweep along the skeleton paths that no cane explains (docs/reconstruction.md, section
// 4e; beyond the paper, s19; on by default since s20). Correspondence only reconstructs what a pair of 2D
// segments yields as a run of epipolar crossings that scores above the match classifier's
// threshold; a cane whose best pair is ill-conditioned, or whose two views disagree on width,
// is left out although every view shows its skeleton. This stage asks all views at once, per
// sample of such a skeleton path, which depth they agree on:
//  1. Per view v, the current canes are projected with their radii; a skeleton point of v's
//     segments (View2D::segments) is explained when it lies within `explained_px` of a cane's
//     projected cross-section. Unexplained runs of at least `min_stretch_px` along a segment,
//     away from the thick (head/trunk) region by `thick_margin_px` and from the view's wire and
//     post lines by `line_margin_px` beyond their half-width, are the stretches.
//  2. A stretch is sampled every `sample_px`. Each sample's ray from camera v is cut by the
//     working volume and hypothesised at depths evenly spaced in inverse depth, so that the
//     projection in the other views moves by about `depth_step_px` per step. The unary cost of
//     a (sample, depth) is, over the other views, the squared skeleton distance of its
//     projection (View2D::centreline_distance_px, bilinear), capped at `cap_px` squared (an
//     occluding view does not dominate), or `missing_view_cost_px2` for a view that does not
//     see the point.
//  3. Viterbi along the stretch (Forney 1973, "The Viterbi algorithm") over states (depth index,
//     last step), with the squared change of step (the second difference of inverse depth)
//     costing `smooth_px2` and steps limited to `max_step` indices: a smooth 3D curve, in
//     O(samples * depths * (2 max_step + 1)^2) time and samples * depths * (2 max_step + 9)
//     bytes (a 1000 px stretch: ~5 MB at the defaults, ~150 MB at the fields' limits).
//  4. A sample is accepted when at least `min_views` views (v included) hold its projection
//     within `accept_px` of their skeleton, every view that sees it does, and it lies farther
//     than `existing_cane_m` from every cane. Runs of accepted samples at least `min_length_m`
//     long, whose RMS skeleton distance in every view stays within `accept_rms_px`, are added
//     as canes (points every ~`point_step_m`, radius from the stretch's (upper) median 2D width:
//     width_px / 2 * depth / fx). They explain the other views' pixels before the next view is
//     swept.
//  5. Against ghosts (a wrong depth finding support in dense skeleton): a sample is ambiguous
//     when a depth more than `unique_exclusion_steps` steps from the chosen one is consistent
//     too (its unary cost at most accept_px squared per other view); a run with a larger share
//     of ambiguous samples than `max_ambiguous_share` is not added, nor is any run of a stretch
//     whose accepted share of samples is below `min_stretch_accepted_share`.
//  6. The check (`check`, on by default): each run's MeasureSweptRun features
//     (depth_sweep_check.h) must pass the `check_*` limits (PassesCheck).
// Thread-safe (a pure function of its inputs).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "core/calibration.h"
#include "core/deadline.h"
#include "core/geometry.h"
#include "workers/reconstruct/depth_sweep_check.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct DepthSweepOptions {
  // Run the stage (reconstruct.h runs it after assembly, before growth). On by default since
  // s20, with the check below: docs/reconstruction.md section 4e gives its figures.
  bool enabled = true;
  double explained_px = 3.0;          // a cane's cross-section this near explains a skeleton px
  double min_stretch_px = 25.0;       // shorter unexplained runs of a segment are left
  int thick_margin_px = 3;            // skeleton points this near the thick region are left
  double line_margin_px = 4.0;        // ... and this far beyond a wire's or post's half-width
  double sample_px = 3.5;             // spacing of the samples along a stretch
  double depth_step_px = 1.0;         // projection shift in the other views per depth step
  int max_depths = 1200;              // at most this many depths per stretch
  double cap_px = 4.0;                // a view's skeleton distance is capped at this
  double missing_view_cost_px2 = 8.0; // cost of an other view that does not see the point
  double smooth_px2 = 1.0;            // cost per squared change of the depth step (indices)
  int max_step = 2;                   // largest depth index change between samples
  double accept_px = 1.5;             // a view supports a sample within this of its skeleton
  int min_views = 3;                  // views (the swept one included) that must support it
  double accept_rms_px = 1.2;         // RMS skeleton distance of a run, per view
  double existing_cane_m = 0.01;      // samples this near a cane are explained in 3D
  double min_length_m = 0.03;         // shorter runs are not added
  double point_step_m = 0.005;        // spacing of an added cane's points
  double max_radius_m = 0.012;        // an added cane's radius is clamped to [0.5 mm, this]
  int image_margin_px = 3;            // a view sees a point this far inside its image
  int unique_exclusion_steps = 4;     // another consistent depth this far away: ambiguous
  double max_ambiguous_share = 1.0;   // runs with more ambiguous samples are dropped (1: off)
  double min_stretch_accepted_share = 0.0;  // stretches accepted less are dropped (0: off)
  // A check on each run before it is added (depth_sweep_check.h, MeasureSweptRun; on by
  // default: docs/reconstruction.md section 4e, "A check on what the sweep adds (s20)"). A run is
  // dropped when any of the limits below fails.
  bool check = true;
  double check_max_width_log_spread = 0.5;  // views' implied radii: max - min of logs (median)
  double check_max_width_log_excess = 10.0; // measured vs projected width, |log| (10: off)
  double check_min_foreground = 0.5;        // min over views: cross-section on foreground (0: off)

  // INVALID_ARGUMENT naming the field ("sweep.<field>") for non-finite or out-of-range values.
  absl::Status Validate() const;
};

// One added cane, for diagnosis.
struct SweptCane {
  int view = -1;                  // the view whose stretch it came from
  double ambiguous_share = 0.0;   // of its samples, those with another consistent depth
  double stretch_accepted_share = 0.0;  // accepted samples of its stretch
  int samples = 0;                // samples of its run
  SweptRunFeatures features;      // MeasureSweptRun of the cane
  bool checked = false;           // it passes the check's limits (whether or not check is on)
};

struct DepthSweepSummary {
  std::vector<int> unexplained_px;  // per view: skeleton points of its segments left unexplained
  std::vector<int> stretches;       // per view: stretches swept
  int samples = 0;                  // samples swept, all views
  int accepted_samples = 0;         // of which accepted
  int added_canes = 0;              // canes appended to the input
  double added_length_m = 0.0;
  int rejected_canes = 0;           // runs the check dropped (options.check)
  double rejected_length_m = 0.0;
  std::vector<SweptCane> added;     // per added cane, in the order appended
};

// Whether `features` pass the options' check_* limits (whatever options.check says).
bool PassesCheck(const SweptRunFeatures& features, const DepthSweepOptions& options);

// Sweeps views[0], views[1], ... in turn as described above and appends the canes found to
// *canes (unoriented polylines, as AssembleCanes returns them; the canes given are not changed).
// views[i] was seen by rig.cameras[i]. INVALID_ARGUMENT naming "views" if their count differs
// from the rig's cameras, or the option's field if options are invalid; DEADLINE_EXCEEDED /
// CANCELLED when `deadline` passes (*canes then holds what was added until then).
absl::Status SweepUnexplainedPaths(const std::vector<View2D>& views, const RigCalibration& rig,
                                   const WorkingVolume& volume, const DepthSweepOptions& options,
                                   const Deadline& deadline, std::vector<Polyline3>* canes,
                                   DepthSweepSummary* summary = nullptr);

}  // namespace vb::reconstruct
