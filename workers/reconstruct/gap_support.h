// SPDX-License-Identifier: Apache-2.0
// Whether the images show wood along a straight 3D line: the evidence connect.h uses to hang a
// cane whose base was not matched across the views on the parent it visibly grows from
// (GapSupportFn; docs/reconstruction.md, "Seen gaps"). Thread-safe (pure function).
#pragma once

#include <vector>

#include "Eigen/Core"
#include "core/calibration.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct GapSupportOptions {
  double step_m = 0.005;   // spacing of the samples along the line
  int tolerance_px = 1;    // a sample is on wood if wood lies within this many pixels (Chebyshev)
  int min_views = 2;       // a sample seen by fewer views (inside the image) counts as unsupported
};

// The fraction in [0, 1] of samples along a-b (ends included) that project onto wood in every
// view in which they fall inside the image, and fall inside at least `min_views` images. A wire
// or post pixel counts as wood: it hides what is behind it. rig.cameras[i] took views[i]; a view
// without a class image (width 0) contradicts nothing (image_probes.h's WoodNear). Returns 0 for
// a non-finite line.
double GapSupport(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                  const std::vector<View2D>& views, const RigCalibration& rig,
                  const GapSupportOptions& options = {});

// Per view (one entry per view, views[i] taken by rig.cameras[i]; 0 for a view without a class
// image), the fraction in [0, 1] of the samples along a-b (ends included) that fall inside that
// image onto wood (options.min_views is not used). All 0 for a non-finite line.
std::vector<double> GapSupportByView(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                     const std::vector<View2D>& views, const RigCalibration& rig,
                                     const GapSupportOptions& options = {});

}  // namespace vb::reconstruct
