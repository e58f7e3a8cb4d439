// SPDX-License-Identifier: Apache-2.0
// Online refinement of the rig's extrinsics from the stop's own images. A rig on a platform that
// bumps along a vineyard row drifts from its calibration by a pixel or so (vibration, heat); at
// the vine's 0.8 m that misplaces triangulated canes by 5-20 mm in depth, half the 10 mm the
// metrics allow. The canes every view sees pin the cameras to one another: the confident matches
// of a first correspondence pass give 3D points, and a bundle adjustment moves those points and
// a small rotation, focal-length scale and principal-point shift of each camera so that every
// point projects onto the skeleton in every view that sees it (distance-to-skeleton residuals,
// robust loss); optionally wires and posts (TrellisLineMatch) join as 3D lines that must
// project onto each view's trace of them. Camera centres stay as calibrated (a drift of the
// mounts is mostly rotation, and with fixed centres the scale is fixed too); weak priors on the
// corrections settle the near-gauge freedom (the whole rig turning together) at the smallest
// correction that explains the images. Fiducials of the platform (RigCalibration::fiducials,
// detected by fiducials.h into View2D::fiducials) are points of known position and pin what the
// canes leave loose: the depth distortion of the whole rig. This goes
// beyond Botterill et al. 2017, who calibrated once with a target; it is standard
// self-calibration (Triggs et al., "Bundle Adjustment - A Modern Synthesis", 2000).
// Thread-safe (pure function).
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/deadline.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/trellis3d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct RigRefineOptions {
  bool enabled = true;              // false: the rig is used as calibrated
  // This camera's pose is held fixed; -1: none, every camera is corrected under the priors. On
  // rigs where every camera drifts, -1 halves the triangulation error of holding one camera
  // (rig_refine_test), which only makes the others agree with the held camera's error.
  int reference_camera = -1;
  double min_probability = 0.8;     // pieces at least this likely to be right give points
  double min_support = 0.8;         // ... and at least this much on the foreground of all views
  double sample_step_m = 0.01;      // spacing of points along each piece
  int max_points = 600;             // evenly thinned to at most this many points
  int min_points = 60;              // fewer points seen by >= 2 views: no refinement
  double reprojection_sd_px = 1.0;  // residual scale (distance to the skeleton)
  double loss_scale_sd = 2.0;       // Cauchy loss scale, in sd (wrong matches fall beyond it)
  double correction_prior_px = 4.0; // weak prior holding each correction near the calibration
  double max_correction_px = 8.0;   // a larger correction (at the focal length) is not trusted
  int max_iterations = 30;
  // Also correct each camera's principal point (2 unknowns, same prior). A shifted principal
  // point looks like a small rotation at the image centre but not at the edges, where the lens
  // distortion is strong and the wires run.
  bool refine_principal_point = true;
  // Wires and posts (TrellisLineMatch) as observations too: each is a 3D line (4 unknowns, plus
  // a sag for wires) that must project onto its trace in every view that sees it. Off: on tuning
  // seeds it changed nothing measurable once made robust (docs/reconstruction.md, 3b).
  bool use_trellis = false;
  double trellis_sd_px = 0.5;              // residual scale of a wire or post to its 2D line
  int trellis_samples = 16;                // points along each wire or post
  bool trellis_wire_sag = true;            // each wire may sag (one more unknown)
  double trellis_max_rms_px = 4.0;         // a wire or post fitted to the canes' rig missing
                                           // its traces by more (RMS) is a mismatch: left out
  // Prior that wires run along the row (x) and posts stand upright (z): sd of the slope of the
  // other two coordinates, m per m; 0: none.
  double trellis_direction_sd = 0.01;
  double trellis_match_residual_px = 6.0;  // the caller matches the trellis lines with this
                                           // TrellisOptions::max_residual_px (a drifted rig
                                           // misses its third view by more than the usual 3 px)
  // The platform's fiducials (View2D::fiducials, positions in RigCalibration::fiducials) as
  // points of known position: each must project onto its detection. They pin what the canes
  // leave loose (the depth distortion of the whole rig).
  bool use_fiducials = true;
  double fiducial_sd_px = 0.3;            // residual scale of a fiducial's detection
  double fiducial_max_residual_px = 2.0;  // a detection missing its fiducial by more after the
                                          // solve is rejected (logged) and the rig solved again
  // With fewer than min_points cane points, the fiducials alone refine the rig if every camera
  // (but the reference) sees at least this many.
  int min_fiducials_per_camera = 4;

  absl::Status Validate() const;
};

struct RigRefineSummary {
  bool applied = false;           // the returned rig differs from the input
  std::string reason;             // why not, when not applied
  int points = 0;                 // 3D points in the adjustment
  int residuals = 0;              // point-view observations
  int trellis_lines = 0;          // wires and posts in the adjustment
  int trellis_residuals = 0;      // their sample-view observations
  int trellis_rejected = 0;       // matches left out as mismatches (trellis_max_rms_px)
  // RMS distance of those samples to their traces, with the lines fitted to the canes' rig, and
  // at the end.
  double trellis_rms_before_px = 0.0;
  double trellis_rms_after_px = 0.0;
  int fiducial_observations = 0;  // fiducial detections in the adjustment (after rejection)
  int fiducials_rejected = 0;     // detections left out (fiducial_max_residual_px)
  double fiducial_rms_before_px = 0.0;  // RMS reprojection error of the kept detections through
  double fiducial_rms_after_px = 0.0;   // the calibrated and the refined rig
  std::vector<std::string> fiducial_log;  // one line per rejected or invalid detection
  double median_before_px = 0.0;  // median distance to the skeleton before and after (Median of
  double median_after_px = 0.0;   // core/statistics.h: the two middle ones' mean for an even count)
  // Per camera: the largest of rotation angle x focal length, focal scale x half width and the
  // principal point's shift, in pixels.
  std::vector<double> correction_px;
};

// The rig with refined camera rotations, focal lengths and principal points. `pieces` are a first
// correspondence pass's output with `rig`. With options.use_fiducials, each view's fiducial
// detections (View2D::fiducials) join as observations of known points; all is solved (Cauchy
// loss), detections then further than fiducial_max_residual_px from their projection are
// rejected (fiducial_log names them) and the rig is solved again. Falls back to `rig` unchanged
// (applied = false, reason set) when there are too few confident points (and too few
// fiducials), the solve fails, or a correction exceeds max_correction_px. A detection whose
// fiducial index is out of range of rig.fiducials is INVALID_ARGUMENT.
// INVALID_ARGUMENT for invalid options or views not matching the rig; DEADLINE_EXCEEDED /
// CANCELLED from `deadline`.
absl::StatusOr<RigCalibration> RefineRig(const std::vector<View2D>& views,
                                         const RigCalibration& rig,
                                         const std::vector<Piece3D>& pieces,
                                         const RigRefineOptions& options, const Deadline& deadline,
                                         RigRefineSummary* summary = nullptr);

// As above, with the wires and posts of `trellis` (MatchTrellisLines with `rig` and
// options.trellis_match_residual_px) as further observations when options.use_trellis: the
// canes refine the rig first, each wire or post is fitted to that rig and left out when it misses
// its traces by more than trellis_max_rms_px, then all are solved together. Each wire's depth is
// free, so the trellis cannot pin a depth distortion of the whole rig (docs/reconstruction.md,
// 3b). A match whose line index is out of range for its view is INVALID_ARGUMENT.
absl::StatusOr<RigCalibration> RefineRig(const std::vector<View2D>& views,
                                         const RigCalibration& rig,
                                         const std::vector<Piece3D>& pieces,
                                         const std::vector<TrellisLineMatch>& trellis,
                                         const RigRefineOptions& options, const Deadline& deadline,
                                         RigRefineSummary* summary = nullptr);


// Re-expresses wire or post lines found in the normalised coordinates of camera `from` in those of
// `to` (the same camera after RefineRig changed its focal length): the lines' supports are mapped
// through their pixels and refitted. begin/end become the ends of the part inside the image; a
// line the camera does not see is left as it is.
void ReexpressLines(const CameraCalibration& from, const CameraCalibration& to,
                    std::vector<Line2D>* lines);

}  // namespace vb::reconstruct
