// SPDX-License-Identifier: Apache-2.0
// Cane assembly (issue 3, step 4, first half): the 3D pieces that correspondence produces
// (piece3d.h) -> whole, unconnected cane polylines. The same stretch of cane usually arrives
// several times (from different view pairs and from overlapping 2D segments), pieces are broken
// at crossings and occlusions, and a few are wrong. After Botterill et al., "A Robot System for
// Pruning Grape Vines" (J. Field Robotics 2017), sec. 3.2.4, where 3D cane pieces are joined into
// canes before the joint optimisation (cane_fit.h).
//
// Method (all greedy, deterministic):
//  1. Every piece is resampled at `step_m` and weighted per sample by probability * support.
//  2. Duplicates are fused: pieces are taken strongest first (weight x length); a piece that runs
//     alongside an existing track (samples within `merge_distance_m`, tangents within
//     `merge_angle_deg`) over at least `min_overlap_m`, and only leaves it where one of the two
//     ends, is averaged into it (weighted, on the track's 1D arc-length grid) and extends it.
//     Otherwise it starts a new track. Tracks that come to overlap are fused the same way.
//  3. Chaining: track ends are joined, best pair first, when the gap is <= `max_gap_m`, the end
//     tangents and the gap direction agree within `max_chain_angle_deg` and the end radii within
//     a factor `max_radius_ratio`; each end joins at most once. Longer gaps, up to
//     `max_long_gap_m` (a cane behind a post in two views), are joined when the tangents and the
//     gap agree within `max_long_gap_angle_deg`. Steps 2-3 repeat until stable.
//  4. Ghosts: a track made of one piece shorter than `min_isolated_length_m`, or any track
//     shorter than `min_cane_length_m` or with less weighted evidence than `min_evidence_m`, is
//     dropped.
//  5. Output: each track resampled at ~`step_m`, points lightly smoothed, radii smoothed along
//     the cane over `radius_smoothing_m` (weighted mean).
// Output polylines have no topology (a later step roots them on the trunk), arbitrary
// orientation, >= 2 points, finite coordinates and radii > 0.
//
// Thread-safe (pure function).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/deadline.h"
#include "core/geometry.h"
#include "workers/reconstruct/piece3d.h"

namespace vb::reconstruct {

struct AssemblyOptions {
  double step_m = 0.01;                 // resampling step of pieces and of the output canes
  double merge_distance_m = 0.008;      // duplicates: max distance of a sample to the other piece
  double merge_angle_deg = 25.0;        // duplicates: max angle between (unoriented) tangents
  double min_overlap_m = 0.02;          // duplicates: min length of the side-by-side stretch
  double end_tolerance_m = 0.03;        // duplicates: a piece may leave a track this far from its end
  double max_gap_m = 0.10;              // chaining: max distance between the joined ends
  double max_chain_angle_deg = 30.0;    // chaining: max angle between end tangents and the gap
  double max_long_gap_m = 0.15;         // chaining: gaps from max_gap_m up to this are joined
  double max_long_gap_angle_deg = 12.0;  // ... only within this angle (a cane behind a post)
  double max_radius_ratio = 2.0;        // chaining: max ratio of the end radii (larger / smaller)
  double tangent_baseline_m = 0.03;     // chord length over which tangents and end radii are taken
  double min_piece_probability = 0.05;  // pieces less likely than this are ignored
  double min_isolated_length_m = 0.12;  // a track of one piece shorter than this is a ghost
  double min_cane_length_m = 0.04;      // any track shorter than this is dropped
  double min_evidence_m = 0.02;         // min sum over samples of probability*support*step
  double radius_smoothing_m = 0.05;     // half-width of the weighted mean of radii along a cane

  // INVALID_ARGUMENT naming the field: non-finite or non-positive lengths and ratios, angles
  // outside (0, 90), max_radius_ratio < 1, min_piece_probability outside [0, 1],
  // max_long_gap_m < max_gap_m.
  absl::Status Validate() const;
};

// Assembles whole canes from `pieces` (see above). Errors:
//  - INVALID_ARGUMENT for invalid options, or a piece with < 2 points, a radius count different
//    from the point count, non-finite coordinates or radii, radii <= 0, or probability/support
//    outside [0, 1] (message names "pieces[i]").
//  - DEADLINE_EXCEEDED / CANCELLED when `deadline` expires; no partial result is returned (the
//    whole stage takes a few ms, so a deadline here means the stop is already lost).
// Empty input gives an empty result.
absl::StatusOr<std::vector<Polyline3>> AssembleCanes(const std::vector<Piece3D>& pieces,
                                                     const AssemblyOptions& options,
                                                     const Deadline& deadline);

}  // namespace vb::reconstruct
