// SPDX-License-Identifier: Apache-2.0
// The trellis part of the 2D structure stage (structure2d.h): wires and posts of one view as
// straight lines in normalised, undistorted image coordinates (CameraCalibration::
// PixelToNormalised), fitted to the wire and post classes of the segmentation.
// Thread-safe (pure functions).
#pragma once

#include <vector>

#include "core/calibration.h"
#include "workers/reconstruct/structure2d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

// Wires: each 8-connected piece of wire pixels (>= min_wire_piece_px) gets RANSAC lines
// (lines2d.h) through its pixels' normalised coordinates; collinear pieces (split by canes or
// posts in front) are merged and refitted; wires whose visible length is under
// min_wire_length_px are dropped. width_px = wire pixels / visible length. Largest support first.
// Preconditions (checked by ExtractStructure): classes match `camera`, options valid.
std::vector<Line2D> ExtractWires(const ClassImage& classes, const CameraCalibration& camera,
                                 const Structure2DOptions& options);

// Posts: each 8-connected post region (>= min_post_area_px) contributes the centre of its span in
// every image row it covers (rows whose span touches the left or right image border are skipped:
// their centre is not the post's); an axis is fitted to those centres by RANSAC + least squares;
// collinear pieces (a post split by a cane or wire in front) merge. Axes tilted more than
// max_post_tilt_deg from vertical or shorter than min_post_length_px are dropped. width_px is the
// median row span. Largest support first. Preconditions as ExtractWires.
std::vector<Line2D> ExtractPosts(const ClassImage& classes, const CameraCalibration& camera,
                                 const Structure2DOptions& options);

}  // namespace vb::reconstruct
