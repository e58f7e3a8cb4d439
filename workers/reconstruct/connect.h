// SPDX-License-Identifier: Apache-2.0
// Connecting reconstructed canes into one tree rooted at the trunk (issue 3 step 6; Botterill
// et al., "A Robot System for Pruning Grape Vines", J. Field Robotics 2017, sec. 3.2: canes are
// joined to their parents by trained join classifiers on gaps, angles and widths).
//
// Method:
//  1. Canes lying mostly inside the trunk or head are those structures seen again and dropped
//     (a long one inside the trunk replaces the silhouette's trunk axis).
//  2. Every end of every cane, as a possible base, is paired with the nearest point of every
//     other cane, of the trunk and of the head's surface within `max_attach_m`: a candidate
//     join, scored by the join classifier (join_classifier.h) on gap, tangent continuity, the
//     side of the parent it meets, width ratio, which end is nearer the head, and so on.
//  3. Every cane takes one parent (the trunk or head, another cane, or none) so that the sum of
//     the log-probabilities of the chosen joins is largest and the joins form a tree: a maximum
//     spanning arborescence (Chu and Liu 1965; Edmonds 1967). "None" has probability
//     `min_join_probability`; a cane with no parent, and every cane hanging on it, is left out
//     (a neighbour's canes, ghosts). Left-out canes are not among the model's canes (never
//     pruned); reconstruct's step 9 (left_out_wood.h) carries the seen wood the model leaves out
//     as its obstacles, which the planner avoids.
//     Optionally (off by default: no gain on the bench, docs/reconstruction.md section 6), a
//     join to a cane that the child visibly goes on across (beyond the paper: the images show
//     wood along the child's line continued past the parent, MeasureCrossing, from the caller's
//     GapSupportFn) is taken for a crossing, not a fork: its probability is multiplied by
//     `crossing_factor`, but not below "none" if it was above it (a cane whose only likely join
//     is a crossing keeps it rather than being lost).
//  3b. Rescued (beyond the paper): the arborescence scores a join to a cane that is itself left
//     out as if that cane were in the tree, so a cane may take a likely join to a left-out cane
//     over a less likely one to the tree and be lost with it. While a left-out cane has a
//     candidate join to the tree (a cane in it, the trunk or the head) at least
//     `rescue_min_probability` likely, the likeliest such join of all is taken, and the canes
//     that hung on the rescued cane by their chosen joins follow it (as they follow a cane kept
//     by step 6). A cane reaching beyond `keep_within_m` is rescued only if it tapers toward
//     the vine's centre by at least `rescue_min_taper` (a neighbour's cane thickens toward it).
//  4. A cane that continues its parent from the parent's tip (a cane broken at a crossing or an
//     occlusion) is appended to it, so that canes come out whole.
//  5. A base near its join point (`max_bridge_m`) gets a first point there. So does a farther
//     one whose gap the images show as wood all along (a GapSupportFn from the caller; beyond
//     the paper): the base was there but was not matched across the views.
//  6. Kept near the vine (beyond the paper): a cane that step 3 leaves without a parent but that
//     lies wholly within `keep_within_m` of the vine's centre along the row (the x of the trunk's
//     top) and is at least `keep_min_length_m` long is taken as this vine's (a neighbour's canes
//     reach into the view from the sides; short ones are mostly ghosts): it hangs on its
//     likeliest candidate join to a cane in the tree, the trunk or the head (joins to canes kept
//     so come after), however unlikely. Left out, its length would be lost to recall. A cane
//     with no candidate join at all (nothing within `max_attach_m`) stays out. A cane reaching
//     farther along the row is kept so too when it tapers away from the vine's centre (its third
//     nearer the centre on average at least `keep_taper_ratio` times as thick as the other end's
//     third, TaperTowardCentre): canes thin from base to tip, so the far piece of this vine's
//     cane thins outward and a neighbour's cane, entering the view tip first, thins inward. Such
//     a cane hangs by its thicker end only.
//     Optionally (off by default: no gain on the bench), steps 3b and 6 are repeated in turn
//     until neither brings another cane into the tree (`repeat_rescue`): a cane kept by step 6
//     may be the likely join that rescues another.
//  6b. Neighbours' leaves dropped (beyond the paper): a cane in the tree without children that
//     reaches beyond `keep_within_m` and is at least `drop_thickening_ratio` times as thick at
//     its far third as at its third nearer the centre is a neighbour's cane hung by its tip on
//     this vine's, and is left out (counted in ConnectSummary::dropped_thickening and unattached).
//  6c. Head exits (beyond the paper; on since s22 with reach 0.3 m and the radius test 3 mm:
//     without that test about half of what it gains on the metric is canes of canes hung on the
//     head; docs/reconstruction.md section 6, "Head exits" and "Head joins that reach farther
//     (s22)"). Canes leaving the head together lose their inner parts in the head's thick
//     foreground, and the outer piece of such a cane, beyond max_attach_m of the head, hangs on
//     a cane it passes. A cane hung on another cane, unless it continues that cane from one of
//     its ends (step 4's gap and angle, but at either end and in either direction: looser than
//     step 4, so a cane hung at the base of a parallel cane stays), or left out (with
//     `head_exit_left_out`, off: it costs precision), whose inner end (the one nearer the head's
//     surface) lies within `head_exit_reach_m` of that surface and whose outward tangent there
//     points at its nearest point (cosine >= `head_exit_min_cos`), with at least `head_exit_min_support` of the
//     straight line to it wood in the images (GapSupportFn; 0: no test, and no function needed),
//     and at least `head_exit_min_radius_m` thick there (its mean radius over 3 cm; 0: no test),
//     hangs on the head by that end; its base is drawn there as step 5 draws any base. The canes
//     hung on it go with it. A fork off a cane beside the head whose base points at that cane,
//     not at the head, keeps its parent; one pointing at the head does not.
// Steps 1-2 are in connect.cc, 3-6 in connect_tree.cc (the arborescence in arborescence.h),
// the geometry they share in connect_geometry.cc. Thread-safe (pure).
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "core/vine_model.h"
#include "workers/reconstruct/join_classifier.h"

namespace vb::reconstruct {

// The fraction in [0, 1] of the straight line from a child's base to a join point that the
// images show as wood. Given by the caller (reconstruct.cc, over the stop's views), so that
// connecting stays free of 2D types. Must be thread-compatible with the call.
using GapSupportFn =
    std::function<double(const Eigen::Vector3d& base, const Eigen::Vector3d& join_point)>;

// What the images show of the join of a base to a join point (MeasureJoinImages, join_images.h;
// past_support is measured by connection itself): the join classifier's image features. Given
// by the caller, as GapSupportFn is. Must be thread-compatible with the call.
using JoinImageFn = std::function<JoinImageEvidence(const Eigen::Vector3d& base,
                                                    const Eigen::Vector3d& join_point)>;

struct ConnectOptions {
  double max_attach_m = 0.15;        // joins with a wider gap than this are not considered
  double max_bridge_m = 0.04;        // a base this near its join point gets a first point there;
                                     // a farther one stays where it was seen (the gap is unseen)
  double head_margin_m = 0.02;       // a gap to the head is measured from this far outside it
  double inside_fraction = 0.7;      // canes with this much of their length inside the trunk or
                                     // head are duplicates of them and dropped
  double spur_length_m = 0.08;       // canes on the head or trunk shorter than this are spurs
  double trunk_axis_min_fraction = 0.3;  // a stereo cane inside the silhouette trunk at least
                                         // this fraction of its length replaces its axis
  double sample_step_m = 0.01;       // spacing of samples along canes for distances
  double min_join_probability = 0.12; // a cane hangs on the tree only by a join this likely
  double rescue_min_probability = 0.12;  // step 3b: a cane left out though it has a join at
                                     // least this likely to the tree hangs on it, and the canes
                                     // hung on it follow; 0 turns this off; otherwise in
                                     // [min_join_probability, 1)
  double rescue_min_taper = 1.0;     // ... a cane reaching beyond keep_within_m only if it is at
                                     // least this much thicker at its end nearer the vine's
                                     // centre (TaperTowardCentre); 0 turns this test off
  bool repeat_rescue = false;        // steps 3b and 6 are repeated, in turn, until neither
                                     // brings another cane into the tree (a cane kept by step 6
                                     // can be the likely join that rescues another); off by
                                     // default: 2 stops of 200 changed on the bench, no gain
                                     // (docs/reconstruction.md section 6, "Repeated")
  bool merge_continuations = true;   // append canes that continue their parent's tip to it
  double continuation_gap_m = 0.02;  // ... joining within this of the tip (arc length)
  double continuation_angle_deg = 35.0;  // ... with tangents within this angle
  JoinWeights join_weights = DefaultJoinWeights();  // the join classifier
  double min_gap_support = 0.9;      // a gap wider than max_bridge_m is drawn when at least this
                                     // fraction of it is wood in the images (GapSupportFn)
  double crossing_factor = 1.0;      // a join to a cane that the child's line, continued past
                                     // the join, visibly crosses (the images show wood along
                                     // crossing_reach_m of it beyond the parent, at least
                                     // crossing_min_support of it: MeasureCrossing) has its
                                     // probability multiplied by this (not below "none" if it
                                     // was above); 1 (the default) turns this off; in (0, 1];
                                     // 0.5 was measured (docs/reconstruction.md section 6)
  double crossing_min_support = 0.9; // ... the fraction of that stretch that must be wood
  double crossing_min_miss_m = 0.0;  // ... and the child's line must pass the parent's axis at
                                     // least this far (MeasureCrossing)
  double crossing_reach_m = 0.03;    // ... the length of the stretch looked at
  double crossing_clearance_m = 0.008;  // ... starting this far past the parent's surface
  double keep_within_m = 0.5;        // a cane left without a parent but lying wholly within this
                                     // of the vine's centre along the row (x) is this vine's: it
                                     // hangs on its likeliest join to the tree; 0 turns this off
  double keep_min_length_m = 0.12;   // ... if it is at least this long (shorter ones are mostly
                                     // ghosts)
  double keep_taper_ratio = 1.2;     // a cane left without a parent that reaches beyond
                                     // keep_within_m is kept as well when it is this much thicker
                                     // at its end nearer the vine's centre (TaperTowardCentre):
                                     // canes taper from base to tip, a neighbour's the other way;
                                     // 0 (or keep_within_m 0) turns this off; otherwise > 1
  double head_exit_reach_m = 0.3;    // step 6c: a cane hung on another cane (or left out) whose
                                     // inner end lies within this of the head's surface, points
                                     // at it and is joined to it by wood in the images hangs on
                                     // the head instead; 0 turns this off (0 before s22)
  double head_exit_min_cos = 0.8;    // ... its outward tangent there within acos(this) of the
                                     // direction to the nearest point of the head's surface
  double head_exit_min_support = 0.0;  // ... at least this fraction of that straight line wood
                                     // (GapSupportFn); 0 (as measured): no test. Its base is
                                     // drawn on the head as step 5 draws any base
  double head_exit_min_radius_m = 0.003;  // ... its mean radius over the 3 cm at that end at
                                     // least this (a fork off a cane is thinner than the head's
                                     // canes, 0.5-0.85 of its parent); 0: no test. 3 mm chosen on
                                     // tuning stops 1300-1339 (docs/reconstruction.md section 6,
                                     // "Head joins that reach farther (s22)")
  bool head_exit_left_out = false;   // ... left-out canes too (they come into the tree); off:
                                     // on the bench they cost precision (neighbours' canes)
  double drop_thickening_ratio = 1.1;  // a cane in the tree without children that reaches beyond
                                     // keep_within_m and is this much thicker at its end farther
                                     // from the vine's centre is a neighbour's and is dropped
                                     // (the new rig shows more of them); 0 (or keep_within_m
                                     // 0) turns this off; otherwise > 1

  absl::Status Validate() const;
};

struct ConnectSummary {
  int attached = 0;       // canes in the tree (trunk excluded)
  int unattached = 0;     // canes left out: no parent, or dropped as a neighbour's leaf
  int kept_near = 0;      // of the attached: canes kept by step 6 (near the vine, no likely join)
  int inside_trunk_or_head = 0;  // canes dropped as duplicates of the trunk or head
  int dropped_thickening = 0;  // canes dropped as neighbours' (drop_thickening_ratio)
  int head_exits = 0;     // of the attached: canes hung on the head by step 6c
  int rescued = 0;        // of the attached: canes hung on the tree by step 3b
                          // (rescue_min_probability), or following a cane kept so or by
                          // step 6
};

// Builds the model's canes: id 1 the trunk (from `trunk`, or if absent the thickest cane reaching
// lowest), then attached canes with ids 2, 3, ... (parents first). `head` is copied into the
// model. An empty input gives a model without canes. `join_images` is looked up only when the
// join weights use the image features (UsesImageFeatures); without it they are 0.
// INVALID_ARGUMENT for invalid options or a cane failing Polyline3::Validate (naming its index).
absl::StatusOr<VineModel> ConnectCanes(const std::vector<Polyline3>& canes,
                                       const std::optional<Polyline3>& trunk,
                                       const HeadModel& head, const ConnectOptions& options,
                                       ConnectSummary* summary = nullptr,
                                       const GapSupportFn& gap_support = {},
                                       const JoinImageFn& join_images = {});

// The mean radius of the third of `cane` (by arc length) whose end is nearer `centre_x` along
// the row, divided by that of the third at the other end: > 1 when the cane thins away from
// the vine's centre. 1 for a cane shorter than 3 cm.
double TaperTowardCentre(const Polyline3& cane, double centre_x);

// What tells a cane crossing another from one growing out of it, for a join of `child` (its
// base the last point if `base_is_last`) to the cane `parent` at `point`: the child's line is
// continued from its base along its outward tangent past the parent.
struct CrossingEvidence {
  double past_support = 0.0;  // the fraction of crossing_reach_m of that line, beginning
                              // crossing_clearance_m beyond the parent's surface, that the
                              // images show as wood (`gap_support`; 0 without it): near 1 when
                              // the child goes on across the parent, near 0 when it ends there;
                              // 0 when the stretch ends on the parent (it runs along it: the
                              // child continues the parent from its tip)
  double miss_m = 0.0;        // the nearest that line (up to where past_support starts) comes
                              // to the parent's axis: a fork meets it, a crossing passes in front
                              // of or behind it
};
CrossingEvidence MeasureCrossing(const Polyline3& child, bool base_is_last,
                                 const Polyline3& parent, const Eigen::Vector3d& point,
                                 const ConnectOptions& options, const GapSupportFn& gap_support);

// Steps 1-2 alone (PrepareCanes, FindJoins), for training the join classifier and diagnosis.
struct PreparedCanes {
  std::optional<Polyline3> trunk;  // base (lowest) to top; nullopt only without any cane
  std::vector<Polyline3> canes;    // the canes that are not the trunk or head seen again
  int inside_trunk_or_head = 0;
};

struct JoinCandidate {
  int child = -1;                  // index into PreparedCanes::canes
  bool base_is_last = false;       // the child's last point would be its base
  int parent = -1;                 // index into PreparedCanes::canes; -1 the trunk or head
  JoinTarget target = JoinTarget::kCane;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // where on the parent
  JoinFeatures features{};
  double probability = 0.0;
};

// Same errors as ConnectCanes.
absl::StatusOr<PreparedCanes> PrepareCanes(const std::vector<Polyline3>& canes,
                                           const std::optional<Polyline3>& trunk,
                                           const HeadModel& head, const ConnectOptions& options);
// With `join_images`, every candidate's image features are measured (for joins to a cane,
// past_support by MeasureCrossing over its gap_all_views); without it they are 0.
std::vector<JoinCandidate> FindJoins(const PreparedCanes& prepared, const HeadModel& head,
                                     const ConnectOptions& options,
                                     const JoinImageFn& join_images = {});
// Steps 3-4 on given joins (ConnectCanes = PrepareCanes, FindJoins, BuildTree). INVALID_ARGUMENT
// for invalid options or a join naming a cane out of range or a probability outside [0, 1].
absl::StatusOr<VineModel> BuildTree(const PreparedCanes& prepared,
                                    const std::vector<JoinCandidate>& joins,
                                    const HeadModel& head, const ConnectOptions& options,
                                    ConnectSummary* summary = nullptr,
                                    const GapSupportFn& gap_support = {});

}  // namespace vb::reconstruct
