// SPDX-License-Identifier: Apache-2.0
// The head and trunk by shape from silhouette (Botterill et al., "A Robot System for Pruning
// Grape Vines", J. Field Robotics 2017, sec. 3.2.4: the head as spheres carved by the views'
// silhouettes). The silhouette is each view's thick foreground (View2D::thick_mask): what
// survives an opening wider than any cane, i.e. the head and the trunk.
//
// Method: an octree of cubes over the working volume. A cube whose bounding sphere projects
// entirely outside the (dilated) silhouette of some view is removed; one that projects entirely
// inside every view is kept whole; the rest are split down to `min_cell_m` and then kept. Kept
// cubes become their bounding spheres, so the union of spheres contains the visual hull, which
// contains the true head and trunk: enclosure is the property the arm's safety needs. The
// largest connected part of the hull is this vine's head and trunk; the slabs where it is as
// narrow as a trunk give the trunk axis, the wider top gives the head. Each side (left, right of
// the trunk) of the head may start lower, where that side alone widens past the trunk's edge.
//
// A trinocular rig looks at the vine from nearly one direction (+-8 deg), so a visual hull is
// long in depth (y). The head's depth is therefore bounded by its measured width and height,
// centred on the trunk axis: an assumption (heads are about as deep as wide) stated in
// docs/reconstruction.md. Posts: their pixels do not carve; a cube hidden by posts in every view
// is kept only within the head's extent (it may be head), and slab widths count only cubes seen
// as wood in every view. Thread-safe (pure function).
#pragma once

#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/deadline.h"
#include "core/vine_model.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct HeadOptions {
  double coarse_cell_m = 0.04;          // octree root cube side
  double min_cell_m = 0.01;             // smallest cube side
  double silhouette_margin_px = 3.0;    // silhouettes grow by this (calibration error, blur)
  int min_views = 3;                    // a cube must be inside the image of at least this many
  double slab_m = 0.02;                 // height of the slabs used to split trunk from head
  double head_width_factor = 1.6;       // a slab wider than this x trunk width is head
  double depth_margin_m = 0.03;         // head depth = head_depth_factor x max(width, height)
                                        // + 2 x this margin
  double head_min_height_m = 0.08;      // the head spans at least this far below the hull top
  double head_overlap_m = 0.04;         // the head reaches this far below the widening
  // Peeling the canes off the silhouettes (head_peel.h; docs/reconstruction.md step 5, s18):
  // pixels of the depth hints' canes (consecutive hints closer than peel_link_m drawn as lines
  // peel_cane_radius_m thick) within peel_depth_px of a silhouette's rim leave that silhouette.
  bool peel_canes = false;
  double peel_cane_radius_m = 0.006;    // the canes' radius as drawn
  double peel_depth_px = 12.0;          // how far into the silhouette a cane is peeled
  double peel_link_m = 0.03;            // consecutive hints closer than this are one cane
  // The head's depth: max(width, height) x this factor + 2 x depth_margin_m.
  double head_depth_factor = 1.0;
  // The head's spheres leave out the smallest cubes whose sphere of this fraction of their
  // bounding radius, about their centre, touches no view's silhouette (s19, docs/reconstruction.md
  // step 5). 1 keeps every leaf whose bounding sphere touches the silhouettes, so the head reaches
  // up to two bounding radii beyond the visual hull; 0 only leaves whose centre projects onto
  // every silhouette (grown by silhouette_margin_px), up to one radius. The hull that gives the
  // trunk, the head's bottom, extent and depth is carved as at 1. In [0, 1]. 0.5 since s19, with
  // the cane bases at the head (head_bases.h; docs/reconstruction.md step 5, "Both on by default").
  double leaf_radius_fraction = 0.5;
  // The tight test above also counts as silhouette, view by view, the wood (foreground) that a
  // disc of this radius fits in, when > 0 (s20, docs/reconstruction.md step 5, "Enclosing every
  // head"). The thick mask is an opening by a wider disc (View2D::thick_mask), which loses narrow
  // parts and corners of a head; the loose leaves' reach covered them, the tight test cut them.
  // Canes thinner than 2 x this radius stay out, so the test stays tight along cane bases.
  // 0: off (s19's test).
  double leaf_wood_radius_px = 0.0;
  // The silhouette that carves (and judges the slabs, the tight test, seen-as-wood) also holds
  // the foreground joined to the thick mask within this many px of foreground (s21,
  // docs/reconstruction.md step 5, "Enclosing every head: the silhouette"): the thick mask is
  // an opening by a 9 px disc, which loses a head's narrow parts and corners, often in one view
  // (tuning stops 1470, 1699: head points up to 18 px outside it, on foreground). 0: off.
  int foreground_reach_px = 0;
  // A cube (or tight-test sphere) held only by that reach, outside the thick mask, in more than
  // this many views is carved: a head part the opening lost in one view is still thick in the
  // others, a cane base is thin in every view. >= 1; 3 or more (a rig of three views) leaves
  // the reach unrestricted.
  int foreground_reach_max_views = 3;
  // Centre the head's depth on the trunk's top (the head sits on the trunk) rather than on the
  // median depth of the depth hints within its extent (s19; off: as before).
  bool head_centre_on_trunk = false;

  absl::Status Validate() const;
};

struct HeadAndTrunk {
  HeadModel head;                 // empty if no thick structure was found
  std::optional<Polyline3> trunk; // base (lowest) to top, at the head; nullopt if none
  int cells_kept = 0;             // octree leaves kept (diagnostics)
};

// rig.cameras[i] belongs to views[i]. `depth_hints` are 3D points of wood triangulated from
// centre lines (the assembled canes' points): where enough fall inside the head's or trunk's
// extent, their median depth centres the head and trunk (more accurate than the hull, whose
// depth is poorly constrained). INVALID_ARGUMENT for a count mismatch, invalid options or
// a view whose thick_mask size disagrees with its calibration; DEADLINE_EXCEEDED. No thick
// foreground anywhere gives an empty result (not an error).
absl::StatusOr<HeadAndTrunk> ReconstructHeadAndTrunk(
    const std::vector<View2D>& views, const RigCalibration& rig, const WorkingVolume& volume,
    const HeadOptions& options, const Deadline& deadline,
    const std::vector<Eigen::Vector3d>& depth_hints = {});

}  // namespace vb::reconstruct
