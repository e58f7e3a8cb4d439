// SPDX-License-Identifier: Apache-2.0
// The parts of the joint refinement (cane_fit.h) shared by its sources: checking the inputs and
// the rejection test (cane_fit_checks.cc), and cutting the trunk's unseen base stretch
// (cane_fit_trunk.cc); the fit itself is in cane_fit.cc. Not part of cane_fit.h's contract.
// Pure functions; thread-safe.
#pragma once

#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "core/calibration.h"
#include "core/vine_model.h"
#include "workers/reconstruct/cane_fit.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct::cane_fit_internal {

// INVALID_ARGUMENT (cane_fit.h, RefineModel's errors) for views that do not match the rig's
// cameras in count or size, or whose maps are missing, mis-sized or not finite ("views[i]: ...").
absl::Status ValidateViews(const std::vector<View2D>& views, const RigCalibration& rig);

// VineModel::Validate(), then INVALID_ARGUMENT "canes[i] (id N): points[k] is beyond 1 km" for
// coordinates or radii beyond 1 km.
absl::Status ValidateModel(const VineModel& model);

// Fraction of a cane's in-image projections (its points in each view of `views`, through
// rig.cameras) that land within tolerance_px of a foreground pixel, and how many projections
// were in an image (the fraction is 0 when none were).
std::pair<double, int> ForegroundFraction(const Polyline3& line, const std::vector<View2D>& views,
                                          const RigCalibration& rig, double tolerance_px);

// The model's canes as the fit starts from them (cane_fit.h): each resampled at
// options.point_spacing_m, a trunk (a cane without a parent) first cut at the top of its unseen
// base stretch when options.trunk_min_views > 0.
struct FitLines {
  std::vector<Polyline3> lines;       // per cane of the model, in its order
  std::vector<WoodObstacle> unseen;   // the cut-off base stretches
  std::vector<size_t> unseen_of;      // per unseen stretch, the index of the trunk it came from
  std::vector<bool> split;            // per cane: it lost its base stretch (no ground pin)
};
FitLines LinesForFit(const VineModel& model, const RigCalibration& rig,
                     const FitOptions& options);

}  // namespace vb::reconstruct::cane_fit_internal
