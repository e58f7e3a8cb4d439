// SPDX-License-Identifier: Apache-2.0
// Strands of two canes lying side by side in one view (beyond the paper; session 23,
// docs/reconstruction.md section 3, "Strand halves"). The foreground there is one strand about
// two canes wide and its skeleton runs between the two axes, so neither cane's epipolar
// crossings fall on it and the strand's width disagrees with either cane's in the other views.
// Where the skeleton is wide and the image shows a seam along it, the stretch gets two half
// paths, w/4 either side of the skeleton across a strand w wide, each w/2 wide (StrandHalf,
// view2d.h), which correspondence searches like segments.
//
// What tells two canes from one thick cane is the image, not the width: a cane is a lit cylinder,
// brightest along its axis, so two side by side are darker at the seam between them than along
// either axis. A stretch is halved where the luminance at the skeleton (averaged over 5 px along
// it) lies at least `min_seam_dip` grey levels below that at both quarter points.
//
// Which half of one view pairs with which half of another is the stereo ordering constraint: two
// canes side by side in both views keep their order, and the crossed pairing triangulates
// between them, 15-40 mm off in depth (CrossesStrands). Without the seam test and the ordering
// test the halves' pieces are right about as often as not and cost more precision than they give
// recall (sessions 18 and 23). Off by default (StrandHalfOptions::enabled).
// Thread-safe (pure functions).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "core/calibration.h"
#include "core/image.h"
#include "workers/reconstruct/match_candidates.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct StrandHalfOptions {
  // Off by default: on tuning seeds 1100-1299 it gained recall and connectivity at little cost in
  // precision, but 1300-1399 and the report seeds did not confirm it (precision fell more than
  // recall rose; docs/reconstruction.md section 3, "Strand halves").
  bool enabled = false;
  // A skeleton point is wide when its width is at least the larger of min_width_px and
  // min_width_ratio x the median width of the view's skeleton points.
  double min_width_px = 6.0;
  double min_width_ratio = 1.5;
  double min_run_px = 20.0;     // shortest stretch of consecutive wide, seamed points halved
  double min_seam_dip = 2.0;    // grey levels (0-255 luminance) the seam lies below both axes

  // INVALID_ARGUMENT naming the field: min_width_px < 1, min_width_ratio < 1, min_run_px < 2,
  // min_seam_dip < 0, or any value not finite.
  absl::Status Validate() const;
};

// The halves of `view`'s segments, from the rgb8 image the view was extracted from, with
// sibling indices into the returned vector; none where a point lies on view.thick_mask (the head
// and trunk), none when disabled. INVALID_ARGUMENT: invalid options, an image that is not rgb8 or
// not the view's size.
absl::StatusOr<std::vector<StrandHalf>> FindStrandHalves(const View2D& view, const Image& image,
                                                         const StrandHalfOptions& options);

// Whether a candidate pairing half `a` (view a, sampled side) with half `b` (view b) crosses the
// two canes: at each hit, the step from the half to its sibling is compared along the epipolar
// direction of increasing depth in each view (in view b along the ray of view a, in view a along
// the ray of view b); a right pairing has them of opposite signs. True when more hits cross than
// keep the order.
bool CrossesStrands(const MatchCandidate& candidate, const StrandHalf& a, const StrandHalf& b,
                    const CameraCalibration& camera_a, const CameraCalibration& camera_b);

}  // namespace vb::reconstruct
