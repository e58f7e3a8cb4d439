// SPDX-License-Identifier: Apache-2.0
// The parts of RefineRig's bundle adjustment (rig_refine.h) beyond the cane points: the unknown
// corrections of each camera with their priors, the platform's fiducials and the wires and posts,
// each added to one Ceres problem over the corrections and each with its own robust rejection.
// Internal to rig_refine*.cc: include from .cc files only (Ceres is a private dependency).
// Not thread-safe: one RefineRig call owns its objects.
#pragma once

#include <array>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "ceres/ceres.h"
#include "core/calibration.h"
#include "Eigen/Core"
#include "workers/reconstruct/ceres_camera.h"
#include "workers/reconstruct/rig_refine.h"
#include "workers/reconstruct/rig_refine_costs.h"
#include "workers/reconstruct/trellis3d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct::rig_refine_internal {

// The bicubic interpolator reads a 4x4 neighbourhood; keep clear of the border.
constexpr double kMarginPx = 2.0;

bool InsideMargin(const CameraCalibration& camera, const Eigen::Vector2d& uv);

// Per camera, its calibrated projection and the corrections solved for (the parameter blocks of
// the problem): rotation as angle-axis in the camera frame; focal scale - 1 and the principal
// point's shift in x and y, pixels. Camera `reference` (== cameras.size() for none) is held fixed.
struct RigUnknowns {
  RigUnknowns(const RigCalibration& rig, size_t reference);

  // A weak prior (CorrectionPrior, RigRefineOptions::correction_prior_px) on the corrections of
  // every camera but the reference that has observations in `problem` and no prior yet; called
  // again when later observations bring in a camera. Holds the principal point fixed unless
  // options.refine_principal_point.
  void AddPriors(const RigCalibration& rig, const RigRefineOptions& options,
                 ceres::Problem* problem);
  // Holds every camera's corrections fixed (constant) or frees all but the reference's.
  void SetCamerasConstant(bool constant, ceres::Problem* problem);

  size_t reference;
  std::vector<Projector> projectors;
  std::vector<std::array<double, 3>> rotations;
  std::vector<std::array<double, 3>> intrinsics;
  std::vector<bool> has_prior;
};

// The fiducial detections of every camera but the reference: points of known platform position.
class FiducialTerms {
 public:
  // No terms unless options.use_fiducials.
  FiducialTerms(const std::vector<View2D>& views, const RigCalibration& rig, size_t reference,
                const RigRefineOptions& options);

  // Whether use_fiducials and every camera but the reference has at least
  // options.min_fiducials_per_camera detections: enough to refine the rig without canes.
  bool suffice() const { return suffice_; }
  bool empty() const { return terms_.empty(); }
  int size() const { return static_cast<int>(terms_.size()); }

  // One residual (FiducialCost) per detection, with `loss` (not owned).
  void AddTo(RigUnknowns* unknowns, ceres::LossFunction* loss, double inv_sd,
             ceres::Problem* problem);
  // Removes from `problem` each detection the corrected rig projects farther than max_px from
  // it, with one line in `log` each; the number removed.
  int RejectOutliers(const RigUnknowns& unknowns, double max_px, ceres::Problem* problem,
                     std::vector<std::string>* log);
  // RMS reprojection error of the detections, pixels: through the corrected and the calibrated rig.
  double RmsCorrected(const RigUnknowns& unknowns) const;
  double RmsCalibrated() const;

 private:
  struct Term {
    size_t view;
    const FiducialObservation* observation;
    ceres::ResidualBlockId id = nullptr;
  };
  const Eigen::Vector3d& Position(const Term& term) const;
  double Error(const Term& term, const RigUnknowns& unknowns) const;

  const RigCalibration& rig_;
  std::vector<Term> terms_;
  bool suffice_ = false;
};

// Wires and posts (TrellisLineMatch): one 3D line per match seen by three or more views (a wire
// also sags), observed at options.trellis_samples points in every view whose 2D trace supports
// them (inside its extent and the image).
class TrellisTerms {
 public:
  TrellisTerms(const std::vector<TrellisLineMatch>& trellis, const RigRefineOptions& options);

  // Adds the observations (TrellisLineCost, `loss` not owned) and direction priors of every match
  // seen by three or more views; the number of lines added.
  int AddTo(const std::vector<View2D>& views, const RigCalibration& rig, RigUnknowns* unknowns,
            ceres::LossFunction* loss, ceres::Problem* problem);
  // Removes from `problem` every line whose traces are missed by more than max_rms_px (RMS; a
  // trace behind a camera counts as a miss); the number removed.
  int RejectMismatches(const RigUnknowns& unknowns, double max_rms_px, ceres::Problem* problem);
  // RMS distance of the samples to their traces, pixels (samples behind a camera left out).
  double Rms(const RigUnknowns& unknowns) const;
  int residuals() const { return static_cast<int>(terms_.size()); }

 private:
  struct Term {
    std::unique_ptr<TrellisLineCost> cost;  // a copy, for the RMS before and after
    size_t view, match;
  };
  // The squared distance of a term's sample to its trace, pixels; false behind the camera.
  bool SquaredErrorPx(const Term& term, const RigUnknowns& unknowns, double* d2) const;

  const std::vector<TrellisLineMatch>& trellis_;
  const RigRefineOptions& options_;
  std::deque<std::vector<Eigen::Vector2d>> curves_;  // per (match, view); costs point into it
  std::vector<std::array<double, 2>> line_ends_;     // the free coordinates of each line's ends
  std::vector<double> sags_;
  std::vector<Term> terms_;
};

}  // namespace vb::reconstruct::rig_refine_internal
