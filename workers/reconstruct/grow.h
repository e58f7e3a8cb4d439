// SPDX-License-Identifier: Apache-2.0
// Two-view growth of cane ends (docs/reconstruction.md, step 4d; beyond the paper). The 2D
// skeleton breaks every cane at junctions and crossings, and correspondence only reconstructs
// what a matched pair of 2D segments covers: the short remainder of a cane beyond a junction
// often gets no 3D piece of its own, so the assembled cane stops at the junction. This stage
// steps each end of each assembled cane outward in 3D along its continued tangent and corrects
// every predicted point by triangulating it against the skeletons of all views at once: it
// minimises, over offsets perpendicular to the step, the sum over views of the truncated squared
// distance of the point's projection to the nearest skeleton point (View2D::centreline_distance_px,
// which has no breaks at junctions), plus a small pull toward the prediction. A step is accepted
// when at least `min_support_views` views hold the corrected point within `support_px` of their
// skeleton and, when only two do, the cane's tangent is not nearly inside their epipolar plane
// (where the pair cannot fix the depth). Growth of an end stops at the first step that fails
// that, or where a view that should see the point (inside its image by `image_margin_px`) shows
// only background around it (a contradiction), where the point lies in a view's thick (head or
// trunk) region, leaves the working volume, turns more than `max_turn_deg` from the end's
// tangent, runs alongside another cane (within `other_cane_m`, directions within
// `along_angle_deg`: that wood is reconstructed already, or the path has switched canes), or
// after `max_length_m`. Grown points take the end's radius.
// Growth alongside another cane (`alongside_max_m` > 0; on by default since s17): where two canes
// lie along each other in the views they share one skeleton path, and the cane that did not get it
// stops where it joins it. Growth then goes on alongside the other cane unless that cane is the
// end's own continuation (the other cane's end lies within `continuation_m` of the point and the
// other cane runs on ahead from it: a tip-to-tip join, which connection makes), the grown point
// comes within `alongside_min_gap_m` of the other cane (it has merged onto it and would double it),
// or the alongside stretch exceeds `alongside_max_m`; while alongside, the correction is pulled
// toward the prediction by `alongside_prior_px_per_mm` (the end keeps its own course). With
// `alongside_require_parting`, an alongside stretch is kept only if growth leaves the other cane
// again (is accepted on evidence beyond it), else cut off where it began.
// Support in bundles (`band_support`, s18; off by default: no recall gain on 1100-1199, step 4d): a
// view also supports a point that lies in a band of wood (foreground, or the wires and posts that
// may hide it) whose half-width through the point (skeleton distance plus distance to the
// background) exceeds the point's projected radius by `band_margin_px` (a single cane's band does
// not: it is a bundle of canes), when the point's projected cross-section lies inside the wood
// (within `band_tolerance_px`). In such bands the correction counts the lesser of the skeleton
// distance and how far the cross-section reaches out of the wood (0 inside), and after a step that
// needed such support it is pulled toward the prediction by `band_prior_px_per_mm`, so the end
// keeps its course through the bundle.
// Refit of the grown stretch (`refit_span_m`, s19; off by default: recall +0.002 and +0.004 on the
// tuning ranges for precision -0.002, step 4d "Depth that does not drift"): after each corrected
// step the last refit_span_m of grown points are refitted jointly to every view's skeleton with a
// bending cost (grow_refit.cc), and the step is checked at its refitted position.
// Thread-safe (pure function of its inputs).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "core/calibration.h"
#include "core/geometry.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct GrowOptions {
  // Run the stage. On by default since session 16: on tuning stops it adds recall and
  // connectivity (+0.013, +0.010-0.014) for some precision (-0.005 to -0.007), which the trunk
  // kept to what the images show (cane_fit.h) pays for (docs/reconstruction.md, step 4d); off,
  // the canes are left as they are.
  bool enabled = true;
  double step_m = 0.005;             // 3D step along the continued tangent
  double tangent_span_m = 0.03;      // the tangent is the chord over this much of the end
  double min_cane_length_m = 0.04;   // shorter canes are not grown
  double max_offset_m = 0.002;       // largest correction of a predicted point, per axis
  double offset_grid_m = 0.0005;     // coarse grid of the correction (refined 4x finer)
  double prior_px_per_mm = 0.0;      // pull toward the prediction: px of cost per mm of offset
  double truncate_px = 4.0;          // a view's squared distance is capped at this squared
  double support_px = 2.0;           // a view supports a point within this of its skeleton
  int min_support_views = 2;         // views that must support each accepted point
  // The end itself must lie within support_px of the skeleton of every view that sees it (and
  // of at least min_support_views): an end the views disagree on is misplaced, and growing it
  // continues its error.
  bool require_end_support = true;
  // An unsupported end is backed off, point by point, up to this far to the first point every
  // view agrees on, and grown from there; the backed-off stretch is replaced only if the growth
  // goes beyond it by min_length_m (s17). 0: such ends are not grown.
  double end_backoff_m = 0.0;
  // A view supports a point only if the skeleton also runs along the step there: the points
  // half a step before and after project within support_along_px of it too (a skeleton that
  // crosses the step's projection, or passes by chance, does not support it). 0: off.
  double support_along_px = 3.0;
  double min_epipolar_angle_deg = 15.0;  // two supports only: tangent vs their epipolar plane
  double max_turn_deg = 35.0;        // largest turn of the grown stretch from the end's tangent
  double other_cane_m = 0.012;       // "alongside another cane": closer than this to it ...
  double along_angle_deg = 30.0;     // ... with directions within this angle
  double max_length_m = 0.15;        // longest growth of one end
  // Where the pipeline runs the stage (reconstruct.h): on the assembled canes, both ends
  // (false), or on the connected model's canes, tips only, before the joint refinement (true).
  bool after_connection = false;
  // Growth that stops on failed evidence (unsupported, contradicted, a sharp turn) is cut back
  // by this much: its last points tend to have drifted off the cane before the evidence failed.
  double trim_m = 0.01;
  double min_length_m = 0.01;        // shorter growths are dropped
  int image_margin_px = 3;           // a view must see a point this far inside its image
  // Growth alongside another cane (s17; see above; on by default: recall +0.0018 and +0.0009 on
  // the two tuning ranges at precision -0.0006 and -0.0011, docs/reconstruction.md step 4d).
  // 0: growth stops alongside another cane, as before.
  double alongside_max_m = 0.1;          // longest stretch grown alongside other canes, per end
  double alongside_min_gap_m = 0.004;    // closer to the other cane than this: stop
  double continuation_m = 0.02;          // the other cane's end this near: its continuation
  double alongside_prior_px_per_mm = 2.0;  // pull toward the prediction while alongside
  bool alongside_require_parting = false;  // keep an alongside stretch only if growth parts
  // Support in bundles (s18; see above; off by default). Where canes lie side by side or overlap
  // in a view the skeleton runs between them or along the bundle's middle, and a cane's own axis
  // projects 2-6 px off it. With `band_support` a view also supports a step whose projected
  // cross-section (the end's radius) lies inside a band of wood wider than the cane (and so do
  // the points half a step before and after it); `band_end_support` applies the same test to the
  // end itself.
  bool band_support = false;
  bool band_end_support = false;
  double band_margin_px = 1.0;         // a band's half-width must exceed the radius by this
  double band_tolerance_px = 0.5;      // the cross-section may reach this far out of the wood
  double band_prior_px_per_mm = 2.0;   // pull toward the prediction after a step in a band
  // Refit of the grown stretch (s19; off by default: recall +0.0020 / +0.0037 on 1100-1199 /
  // 1200-1299 at precision -0.0023 / -0.0022, docs/reconstruction.md step 4d, "Depth that does
  // not drift"): after each corrected step, the last `refit_span_m` of grown points (the new
  // one included) are refitted jointly against every view's skeleton (nearest along the normal to
  // the projected cane, within refit_search_px) with a bending cost, anchored by the two points
  // of curve before them; the step is then checked at its refitted position (the earlier grown
  // points it moves are not checked again).
  // Where only two views hold the point and the step runs near their epipolar plane the views
  // leave the depth free, and the bending cost holds the curve's course there. 0: off.
  double refit_span_m = 0.0;
  // The end's own last points within this of it may move in the refit too (replaced only if the
  // growth is kept): the end growth starts from is often off in depth itself. 0: they stay.
  double refit_end_m = 0.0;
  double refit_search_px = 4.0;        // a view's skeleton is looked for this far off
  double refit_smooth_px_per_mm = 2.0; // cost (px) per mm a point lies off its neighbours' chord

  // INVALID_ARGUMENT naming the field for non-finite or out-of-range values.
  absl::Status Validate() const;
};

// Why the growth of an end stopped (GrowSummary's counts, in order).
enum class GrowStop { kEndUnsupported, kUnsupported, kContradicted, kAlongside, kThick, kTurned,
                      kOutside, kCapped };

// One end looked at (for diagnosis): cane index in the input, which end (0: the last point, 1:
// the first), why growth stopped, the point it stopped at (the rejected step; the end itself when
// it was not grown), the cane it ran alongside (kAlongside, when growth stopped at that cane;
// -1 otherwise, and when `alongside_require_parting` dropped a stretch that never parted: then
// the stop point is the last step), and the length kept.
struct GrowEnd {
  int cane = -1;
  int side = 0;
  GrowStop stop = GrowStop::kCapped;
  Eigen::Vector3d stop_point = Eigen::Vector3d::Zero();
  int other_cane = -1;
  double grown_m = 0.0;      // length added to this end (0 if nothing was kept)
  double alongside_m = 0.0;  // of which grown alongside another cane
  Eigen::Vector3d start_point = Eigen::Vector3d::Zero();  // the end growth started from
  std::vector<Eigen::Vector3d> steps;  // every accepted step, in order, before the trim
};

struct GrowSummary {
  int ends_tried = 0;      // cane ends looked at
  int ends_grown = 0;      // ends given at least min_length_m
  int contradicted = 0;    // growths stopped by a view's background
  int unsupported = 0;     // ... by fewer than min_support_views supporting views
  int end_unsupported = 0; // ends not grown because the views disagree on the end itself
  int alongside = 0;       // ... by running alongside another cane
  int thick = 0;           // ... by the thick (head/trunk) region
  int turned = 0;          // ... by a sharp turn
  int outside = 0;         // ... by leaving the working volume
  int capped = 0;          // ... by max_length_m
  double added_length_m = 0.0;
  int ends_alongside = 0;           // ends grown on alongside another cane (alongside_max_m > 0)
  double alongside_length_m = 0.0;  // length kept that was grown alongside another cane
  std::vector<GrowEnd> ends;        // every end tried, in order
};

// Grows both ends (the last point only when `tips_only`) of every cane in `canes` (unoriented
// polylines, as AssembleCanes returns them) in place, as described above; grown stretches are
// appended at the cane's own point spacing. views[i] was seen by rig.cameras[i]. INVALID_ARGUMENT
// naming "views" if their count differs from the rig's cameras, or the option's field if options
// are invalid.
absl::Status GrowCaneEnds(const std::vector<View2D>& views, const RigCalibration& rig,
                          const WorkingVolume& volume, const GrowOptions& options,
                          std::vector<Polyline3>* canes, GrowSummary* summary = nullptr,
                          bool tips_only = false);

}  // namespace vb::reconstruct
