// SPDX-License-Identifier: Apache-2.0
// Internals of the depth sweep (depth_sweep.h), shared by its two source files. Not an API.
#pragma once

#include <vector>

#include "Eigen/Core"
#include "core/calibration.h"
#include "workers/reconstruct/depth_sweep.h"
#include "workers/reconstruct/piece3d.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct::depth_sweep_internal {

// The depth of each sample of a stretch along its ray (inverse ray distance q, 0 where the
// sample has none: its ray misses the volume, or no other view sees it at any depth) and whether
// another depth more than options.unique_exclusion_steps steps away is consistent too.
struct StretchDepths {
  std::vector<double> q;
  std::vector<bool> ambiguous;
};

// Steps 2-3 of depth_sweep.h for the samples of one stretch of view v, given their unit rays
// from camera v (platform frame): depths evenly spaced in inverse depth over the volume, the
// capped skeleton distances of the other views as unary costs, the Viterbi path over (depth,
// step), refined between steps by a parabola and smoothed over +-2 samples.
StretchDepths SweepStretch(const std::vector<Eigen::Vector3d>& rays, int v,
                           const std::vector<View2D>& views, const RigCalibration& rig,
                           const WorkingVolume& volume, const DepthSweepOptions& options);

}  // namespace vb::reconstruct::depth_sweep_internal
