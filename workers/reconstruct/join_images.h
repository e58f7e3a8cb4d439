// SPDX-License-Identifier: Apache-2.0
// What the images show of a candidate join (join_classifier.h, JoinImageEvidence): whether the
// gap between a cane's base and the point where it would join its parent projects onto wood,
// and whether the skeleton has a junction where the join point projects. Botterill et al.
// (J. Field Robotics 2017, sec. 3.2.2) join canes in 2D on image features; here the 3D join
// looks the images up. Thread-safe (pure function).
#pragma once

#include <vector>

#include "Eigen/Core"
#include "absl/status/status.h"
#include "core/calibration.h"
#include "workers/reconstruct/gap_support.h"
#include "workers/reconstruct/join_classifier.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct JoinImageOptions {
  GapSupportOptions gap;             // sampling of the gap (GapSupport, GapSupportByView)
  double junction_radius_px = 5.0;   // a junction node this near the projected join point counts

  // INVALID_ARGUMENT naming the field ("join_images.gap.step_m must be finite and > 0, is 0"):
  // gap.step_m not finite and > 0; gap.tolerance_px, gap.min_views or junction_radius_px not
  // finite and >= 0.
  absl::Status Validate() const;
};

// The evidence of the join of a base at `base` to a parent at `point`: gap_all_views
// (GapSupport), gap_best_two (the second largest of GapSupportByView; 0 with fewer than two
// views), junction_views (of the views with a class image in which `point` falls inside the
// image, the fraction that have a skeleton node with three or more segments within
// junction_radius_px of its projection; 0 if none). past_support is left 0 (connection measures
// it). rig.cameras[i] took views[i]. All 0 for a non-finite base or point. `options` must be
// valid (Validate).
JoinImageEvidence MeasureJoinImages(const Eigen::Vector3d& base, const Eigen::Vector3d& point,
                                    const std::vector<View2D>& views, const RigCalibration& rig,
                                    const JoinImageOptions& options = {});

}  // namespace vb::reconstruct
