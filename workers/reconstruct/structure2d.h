// SPDX-License-Identifier: Apache-2.0
// Stage 2 of reconstruction (docs/reconstruction.md, issue 3): the 2D structure of one view from
// its per-pixel classes. After Botterill et al., "A Robot System for Pruning Grape Vines"
// (J. Field Robotics 2017) section 3.2.2, with one change: canes are the skeleton of the
// foreground (thinning, graph tracing, spur pruning) rather than pairs of outline edges, because
// a skeleton gives centre lines and junctions directly and keeps crossing canes apart.
//
//  - Foreground: small specks dropped, pinholes filled, and the 1-4 px gaps a wire in front cuts
//    into a cane bridged (wire pixels with foreground on both sides across the wire).
//  - segments/nodes: the skeleton (skeleton.h) as a graph of ends and junctions; spurs shorter
//    than the local width pruned; every point re-centred on the foreground cross-section normal
//    to the path (sub-pixel, at most max_centre_shift_px), lightly smoothed, ~1-1.4 px apart,
//    with the cross-section width (or 2 * distance-to-background - 1 where the cross-section is
//    not clean, as at junctions); free ends extended to the foreground boundary. A crossing of
//    two canes becomes a junction of four segments (or two junctions joined by a short segment
//    when the canes cross at a shallow angle).
//  - wires: RANSAC + least-squares lines through the wire pixels of each connected piece, in
//    normalised undistorted coordinates, collinear pieces merged, short lines rejected.
//  - posts: the axis through the row centres of each post-class region, likewise.
//  - thick_mask: opening of the foreground with a disc of radius thick_radius_px.
//  - centreline_distance_px: distance to the nearest segment, capped.
//
// Thread-safe (a pure function; it allocates its own buffers).
#pragma once

#include <cstdint>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/deadline.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct Structure2DOptions {
  int min_speck_area_px = 8;           // foreground components smaller than this are dropped
  int max_pinhole_area_px = 8;         // non-foreground holes up to this area become foreground
  int max_wire_gap_px = 4;             // wire runs up to this long between foreground are bridged
  double spur_width_factor = 1.0;      // end branches shorter than this * local width are pruned
  double min_spur_px = 3.0;            // end branches shorter than this are always pruned
  double junction_merge_factor = 0.6;  // junctions joined by < this * local width become one
  double min_segment_px = 6.0;         // pieces with two free ends shorter than this are dropped
  double max_centre_shift_px = 1.5;    // cross-section centring moves a point at most this far
  int smoothing_passes = 4;            // [1 2 1] / 4 passes over each segment's points
  double thick_radius_px = 9.0;        // opening disc radius for thick_mask (> widest cane / 2)
  int min_wire_piece_px = 15;          // connected wire pieces smaller than this are ignored
  double wire_inlier_px = 1.5;         // RANSAC inlier distance of wire pixels to their line
  double wire_merge_px = 4.0;          // pieces whose ends lie this close to a wire's line join it
  double wire_merge_angle_deg = 4.0;   // ... if their directions differ by less than this
  double min_wire_length_px = 80.0;    // wires with less visible length than this are rejected
  int min_post_area_px = 300;          // post-class regions smaller than this are ignored
  double post_inlier_px = 3.0;         // RANSAC inlier distance of post row centres to the axis
  double post_merge_px = 6.0;          // post pieces whose ends lie this close to an axis join it
  double min_post_length_px = 60.0;    // posts with less visible length than this are rejected
  double max_post_tilt_deg = 30.0;     // axes leaning more than this from vertical are rejected
  int ransac_iterations = 64;          // RANSAC hypotheses per line
  uint64_t seed = 1;                   // RANSAC seed (results are deterministic in it)

  // INVALID_ARGUMENT naming the field: negative areas or lengths, non-finite values,
  // thick_radius_px < 1, wire/post inlier or merge distances <= 0, angles outside (0, 90),
  // smoothing_passes outside [0, 20], ransac_iterations < 1.
  absl::Status Validate() const;
};

// The View2D of one image: `classes` (copied into the result, unchanged), segments, nodes, wires,
// posts, thick_mask, centreline_distance_px (see the file comment and view2d.h).
// Errors: INVALID_ARGUMENT for invalid options or calibration, a class image whose size differs
// from the calibration's image size (or whose data size is not width * height), or class values
// outside PixelClass; DEADLINE_EXCEEDED or CANCELLED from `deadline` (polled between steps);
// INTERNAL if OpenCV throws.
absl::StatusOr<View2D> ExtractStructure(const ClassImage& classes,
                                        const CameraCalibration& camera,
                                        const Structure2DOptions& options,
                                        const Deadline& deadline);

}  // namespace vb::reconstruct
