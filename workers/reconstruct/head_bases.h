// SPDX-License-Identifier: Apache-2.0
// Cane bases at the head (docs/reconstruction.md step 5, "Cane bases at the head (s19)"; beyond
// the paper). Where canes leave the head they lie side by side over the head's thick foreground,
// so their first centimetres have no skeleton of their own, correspondence matches nothing there
// and growth (grow.h) stops at the thick region: the assembled canes start several centimetres
// out, although a pruner cuts about 1 cm from the base.
//
// This stage runs after the head (head.h) and before connection (connect.h). Each cane end lying
// within `reach_m` of the head's spheres whose outward direction points at the head (cosine at
// least `min_cos` with the direction to the nearest point of the spheres' surface, or to their
// centre for an end already inside) is stepped on, `step_m` at a time, along its tangent (the
// chord over its last `tangent_span_m`). Each predicted point is corrected by at most
// `max_offset_m` across the step toward the skeleton of the views that do not show it in their
// thick region (View2D::centreline_distance_px, truncated at `truncate_px`; the thick views carry
// no cane of their own there), and must project onto wood (foreground, or a wire or post that may
// hide it, within `wood_px`) in every view whose image holds it. The extension is kept when it
// reaches the head: the point lies in the thick region of at least `min_thick_views` views (where
// the cane meets the head's silhouette; 0 turns this test off) or it has run `max_inside_m` (arc
// length) inside the head's spheres. It is dropped
// whole (the end stays as it was) when a view shows no wood, the corrected course turns more than
// `max_turn_deg` from the end's tangent, or `max_length_m` is exceeded first: wood is never added
// where a view contradicts it. A kept extension is dropped too when its points lie, on average,
// more than `max_skeleton_px` from the skeletons of the views that see them outside their thick
// region (0: no such test). With `curve_gain` > 0 the prediction turns, step by step, as the
// circle through the end's last two tangent spans does (times curve_gain), instead of running
// straight (s20: docs/reconstruction.md step 5, "Cane bases at the head: where to stop").
// New points take the end's radius.
// Thread-safe (pure function of its inputs).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "core/calibration.h"
#include "core/geometry.h"
#include "core/vine_model.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct HeadBasesOptions {
  // Run the stage. On by default since s19, with HeadOptions::leaf_radius_fraction 0.5: together
  // they cut the true cuts missed by 0.05 on both tuning ranges at 0.005 of precision
  // (docs/reconstruction.md step 5, "Both on by default").
  bool enabled = true;
  double reach_m = 0.12;           // ends this near the head's spheres' surface are looked at
  double min_cos = 0.5;            // ... if their outward direction points at the head this well
  double step_m = 0.005;           // length of one step
  double tangent_span_m = 0.03;    // the end's tangent is the chord over this much of it
  double max_offset_m = 0.001;     // largest correction of a predicted point, per axis
  double truncate_px = 4.0;        // a view's skeleton distance is capped at this in the correction
  double wood_px = 3.0;            // a view sees wood at a point with wood within this radius
  int min_thick_views = 2;         // the head is reached where this many views show thick wood
                                   // (0: never)
  double max_inside_m = 0.03;      // ... or after running this far inside the head's spheres
  double max_turn_deg = 45.0;      // largest turn of the extension from the end's tangent
  double max_length_m = 0.12;      // longest extension of one end
  double min_cane_length_m = 0.03; // shorter canes are not extended
  // The course's curvature as a fraction of the end's (0: straight along the tangent, s19; 1:
  // the circle through the end's last two tangent spans, continued).
  double curve_gain = 0.0;
  // An extension kept by the stops above is dropped when its points' mean skeleton distance (each
  // the mean over the views holding it outside their thick region, capped at 10 px; 0 where none
  // does) exceeds this (px; 0: no such test).
  double max_skeleton_px = 0.0;

  // INVALID_ARGUMENT naming the field for non-finite or out-of-range values.
  absl::Status Validate() const;
};

// Why an end's extension ended (HeadBasesSummary's counts).
enum class HeadBaseStop { kNotTried, kReachedThick, kReachedInside, kNoWood, kTurned, kTooLong,
                          kOutsideImages, kOffSkeleton };

// One end tried (for diagnosis: HeadBases.DISABLED_Report): where it started and what was added.
struct HeadBaseExtension {
  Eigen::Vector3d end = Eigen::Vector3d::Zero();      // the end before extension
  Eigen::Vector3d tangent = Eigen::Vector3d::UnitX(); // its outward unit tangent
  double end_distance_m = 0.0;  // signed distance from the end to the head's spheres
  double bend_deg = 0.0;        // angle between the chords of the end's last two tangent spans
  HeadBaseStop stop = HeadBaseStop::kNotTried;
  // Every point the course reached (added to the cane only when `stop` is kReachedThick or
  // kReachedInside), and per point: the arc length run inside the head's spheres, the views
  // showing it thick and the distance to the nearest other cane (as the canes were before this
  // stage).
  std::vector<Eigen::Vector3d> points;
  std::vector<double> inside_m;
  std::vector<int> thick_views;
  std::vector<double> other_cane_m;
  std::vector<int> correcting_views;   // views that held the point outside their thick region
  std::vector<double> skeleton_px;     // their mean skeleton distance at it, each capped at 10 px
                                       // (0 where no view does)
  std::vector<int> on_skeleton_views;  // ... of them, those with the skeleton within 2 px
};

struct HeadBasesSummary {
  int ends_tried = 0;        // ends near the head pointing at it
  int ends_extended = 0;     // of those, extended to the head
  int reached_thick = 0;     // ... stopped at min_thick_views thick views
  int reached_inside = 0;    // ... stopped after max_inside_m inside the head's spheres
  int no_wood = 0;           // dropped: a view showed no wood
  int turned = 0;            // dropped: turned more than max_turn_deg
  int too_long = 0;          // dropped: max_length_m without reaching the head
  int outside_images = 0;    // dropped: fewer than two views' images held a point
  int off_skeleton = 0;      // dropped: mean skeleton distance above max_skeleton_px
  double added_length_m = 0.0;
  std::vector<HeadBaseExtension> extensions;  // every end tried, in the order tried
};

// Extends, in place, the ends of `canes` (unoriented polylines, as AssembleCanes and
// GrowCaneEnds leave them) that point at `head` to where they meet it, as described above.
// views[i] was seen by rig.cameras[i]. Does nothing when options.enabled is false or `head` has
// no spheres. INVALID_ARGUMENT naming "views" if their count differs from the rig's cameras or a
// view's thick_mask size disagrees with its image (a missing or mis-sized skeleton distance map
// is read as image_probes.h says), or naming the option's field if options are invalid.
absl::Status ExtendBasesToHead(const std::vector<View2D>& views, const RigCalibration& rig,
                               const HeadModel& head, const HeadBasesOptions& options,
                               std::vector<Polyline3>* canes,
                               HeadBasesSummary* summary = nullptr);

}  // namespace vb::reconstruct
