// SPDX-License-Identifier: Apache-2.0
// Single-view extension (docs/reconstruction.md, step 4c; beyond the paper): every stage before
// this one needs a cane in two views, so a cane whose tip runs out of all images but one (along
// the row beyond the two-view strip, or hidden from the other cameras) ends where the second view
// lost it. This stage follows each cane tip's 2D continuation along the skeleton of a view that
// shows wood beyond the projected tip, and puts each continuation point on its camera ray at the
// depth that continues the 3D cane most smoothly: least squares on the depths t_i of
// X_i = C + t_i r_i, minimising the second differences of the sequence (the cane's last 3D
// points, then X_1..X_n) with a weak pull toward the vine plane. The problem is linear in the
// depths; its covariance gives each depth's standard deviation, and the extension stops where
// that passes `max_depth_sd_m` (the extrapolation grows uncertain with distance from the tip).
// It also stops where another camera that should see the point shows background around it (a
// contradiction), where the path runs onto another model cane, leaves the working volume, or
// turns sharply at a junction. Most wrong added length continues a tip that was already wrong
// (a neighbour's cane, a mis-depthed end), so tips likely to be wrong are not extended: far
// along the row from the trunk, pointing across the row, or lying off a view's skeleton.
// Extended stretches are appended to the canes' polylines; vine_model.v1 has no field to mark
// them, so ExtendSummary counts them. Thread-safe (pure function of its inputs).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "core/calibration.h"
#include "core/vine_model.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct ExtendOptions {
  // Run the stage (on by default since session 16: with the which-tips rules below it adds
  // recall at unchanged precision on tuning stops, docs/reconstruction.md, step 4c); off, the
  // model is left as it is.
  bool enabled = true;
  double step_m = 0.005;            // 3D spacing of the continuation points (and anchors)
  int anchor_points = 4;            // the cane's last points (at step_m) that seed the depths
  double anchor_span_m = 0.05;      // the anchors lie on a line fitted to this much of the cane
                                    // before its tip (0: the cane's own points)
  double min_cane_length_m = 0.04;  // shorter canes are not extended (too little to continue)
  double snap_px = 3.0;             // the projected tip must lie this close to a skeleton path
  double second_difference_sd_m = 0.001;  // prior sd of a second difference (bending per step)
  double plane_sd_m = 0.1;                // prior sd of a point's distance to the vine plane (y)
  double max_depth_sd_m = 0.010;          // stop where a depth's predicted sd passes this (6 mm
                                          // until s22: docs/reconstruction.md, section 10)
  double max_length_m = 0.3;              // longest extension of one tip
  double min_length_m = 0.015;            // shorter extensions are dropped
  double max_turn_rad = 0.6;              // the largest turn of the 2D path at a junction
  double other_cane_px = 2.0;             // stop within this (plus its projected radius) of another
                                          // model cane's projection
  double background_px = 0.0;             // a view contradicts a point if no wood lies within this
                                          // (plus the projected radius) of its projection
  int image_margin_px = 3;  // a view must see a point this far inside to contradict it
  // Which tips are extended (docs/reconstruction.md, step 4c, "Which tips"; 0 turns a rule off).
  double max_tip_row_distance_m = 0.0;  // skip a tip farther than this along the row (|x|) from
                                        // the trunk's top: neighbours' canes overlap there; off
                                        // since s26 (0.9 before: docs/reconstruction.md,
                                        // section 10, "The row rule off (s26)")
  double max_tip_out_of_plane = 0.3;    // skip a tip whose unit tangent's component across the
                                        // row (|y|, toward the cameras) passes this
  double support_span_m = 0.03;         // the cane's last stretch checked against the skeletons
  double max_support_px = 0.0;          // skip a tip whose last support_span_m lies farther than
                                        // this from the skeleton (mean distance, px, over its
                                        // points inside the image) in some view; off by default
                                        // since s22 (0.8 before: docs/reconstruction.md,
                                        // section 10)

  // INVALID_ARGUMENT naming the field for non-finite or out-of-range values.
  absl::Status Validate() const;
};

// Why an extension ended (the first rule that stopped it).
enum class ExtendStop {
  kPathEnd,       // the 2D path ended (a skeleton end, a junction without a smooth way on)
  kMaxLength,     // max_length_m reached
  kOtherCane,     // the path ran onto another model cane's projection
  kUncertain,     // the depth's predicted sd passed max_depth_sd_m
  kVolume,        // the point left the working volume
  kContradicted,  // another view shows background where the point projects
};

// One extended tip.
struct ExtendedTip {
  int cane = -1;         // index into VineModel::canes
  int view = -1;         // the view whose skeleton was followed
  int first_point = 0;   // index in the cane's polyline of the first added point
  int points = 0;        // points added
  double length_m = 0.0;
  ExtendStop stop = ExtendStop::kPathEnd;
};

struct ExtendSummary {
  int tips_tried = 0;     // cane tips looked at
  int tips_extended = 0;  // tips given an extension
  int tips_skipped = 0;   // tips the which-tips rules (row distance, out of plane, support) skip
  int contradicted = 0;   // extensions cut short by another view's background
  int uncertain = 0;      // extensions cut short by the depth's predicted sd
  double added_length_m = 0.0;
  std::vector<ExtendedTip> extended;  // one per extended tip, in cane order
};

// Extends the tips of the canes (kind kCane) of `model` in place, as described above. views[i]
// was seen by rig.cameras[i]; the vine plane is the median y of the model's cane points.
// Points are added only inside `volume`. INVALID_ARGUMENT naming "views" if their count differs
// from the rig's cameras, or the option's field if options are invalid.
absl::Status ExtendCanes(const std::vector<View2D>& views, const RigCalibration& rig,
                         const WorkingVolume& volume, const ExtendOptions& options,
                         VineModel* model, ExtendSummary* summary = nullptr);

// How closely the skeletons follow a cane's last stretch (the support rule of "Which tips"):
// samples every 5 mm from arc length (length - span_m) (0 if shorter) to the end of `line`,
// projected into each view (rig.cameras[i] saw views[i]) that has its skeleton distance map
// (View2D::centreline_distance_px); in each, the mean skeleton distance (px, at the nearest
// pixel) of the samples that fall inside the image.
struct TipSupport {
  double worst_mean_px = 0.0;  // the largest such mean over the views (0 if no view sees any)
  int views = 0;               // views in whose image at least one sample falls
};
// `line` must have at least one point; views.size() must not exceed rig.cameras.size().
TipSupport TipSupportOf(const Polyline3& line, const std::vector<View2D>& views,
                        const RigCalibration& rig, double span_m);

}  // namespace vb::reconstruct
