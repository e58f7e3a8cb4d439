// SPDX-License-Identifier: Apache-2.0
// Wires and posts in 3D from their 2D lines (View2D::wires, View2D::posts). A line in one view
// back-projects to a plane through the camera centre; two views' planes meet in the 3D line.
// Candidates from every pair of views are checked against the other views' lines, then chosen
// greedily, best first, each 2D line used once. With three or more views, a candidate that no
// other view confirms is dropped. Pairs whose planes meet at a grazing angle
// (horizontal wires seen by horizontally separated cameras) are skipped: the trinocular rig's
// upper camera gives every wire a well-conditioned pair. Thread-safe (pure functions).
#pragma once

#include <vector>

#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/vine_model.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/view2d.h"
#include "workers/reconstruct/wire_fit.h"

namespace vb::reconstruct {

struct TrellisOptions {
  double min_plane_angle_deg = 3.0;   // planes meeting at less than this are not intersected
  double max_residual_px = 3.0;       // a third view's line must lie this close (RMS) to the
                                      // candidate's projection to confirm it
  double duplicate_distance_m = 0.02; // candidates this close to a chosen wire are duplicates
  double max_wire_slope = 0.2;        // wires run along the row: |dz|, |dy| per metre of x
  double max_post_tilt = 0.3;         // posts stand up: |dx|, |dy| per metre of z
  bool fit_all_views = true;          // a chosen line is refitted to the planes of every view
                                      // that saw it (not only the two it was built from)
  bool fit_sag = true;                // a chosen wire becomes a polyline fitted to the observed
                                      // wire centres of every view (wire_fit.h): wires sag
  WireFitOptions wire_fit;

  absl::Status Validate() const;
};

struct Trellis {
  // ids 1, 2, ... from the lowest; from the volume's x min to its x max: two points, or with
  // fit_sag the knots of the fitted polyline (two points where too few centres support a fit)
  std::vector<Wire> wires;
  std::vector<Post> posts;  // ids 1, 2, ... along x; from the ground to the volume's top
};

// rig.cameras[i] belongs to views[i]. INVALID_ARGUMENT for a count mismatch or bad options.
absl::StatusOr<Trellis> ReconstructTrellis(const std::vector<View2D>& views,
                                           const RigCalibration& rig, const WorkingVolume& volume,
                                           const TrellisOptions& options = {});

// A wire or post matched across views: its 3D segment as ReconstructTrellis would place it, and the
// 2D line of each view that it was built from or confirmed by. Input to RefineRig
// (rig_refine.h), which uses the trellis as observations of the rig.
struct TrellisLineMatch {
  bool post = false;                               // false: a wire (along x); true: a post (along z)
  Eigen::Vector3d a = Eigen::Vector3d::Zero();     // ends, clipped to the volume along the main axis
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  std::vector<int> lines;                          // per view: index into View2D::wires (or posts), -1: none
};

// The wires, then the posts, that ReconstructTrellis would choose, with their 2D lines. Errors as
// ReconstructTrellis.
absl::StatusOr<std::vector<TrellisLineMatch>> MatchTrellisLines(const std::vector<View2D>& views,
                                                                const RigCalibration& rig,
                                                                const WorkingVolume& volume,
                                                                const TrellisOptions& options = {});

}  // namespace vb::reconstruct
