// SPDX-License-Identifier: Apache-2.0
// Diagnosis support, not part of the stage (docs/reconstruction.md, step 4d, "Depth that does not
// drift"): how far the points grown by GrowCaneEnds (grow.h) lie off their own true cane, and in
// which direction, on rendered stops with known truth. Used by Grow.DISABLED_Report with
// VB_GROW_DRIFT=1 (grow_diagnose_test.cc).
#pragma once

#include <vector>

#include "core/calibration.h"
#include "core/vine_model.h"
#include "workers/reconstruct/grow.h"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

// Running sums of the grown points' error against the truth, by the step number from the start
// end, the number of views holding the point within support_px of their skeleton, the step's
// angle to the two supporting views' epipolar plane, and how far off the start end itself is.
// An end counts when its start lies within 10 mm of one of the vine's true canes (its own cane:
// the nearest); each accepted step (GrowEnd::steps, before the trim) is then compared with the
// nearest point of that cane. "Depth" is the error's component along the ray from the mean of the
// camera centres; "lateral" the rest.
class DriftTally {
 public:
  void Add(const VineModel& truth, const std::vector<View2D>& views, const RigCalibration& rig,
           const GrowOptions& options, const GrowSummary& summary);
  void Print() const;

 private:
  struct Bin {
    int points = 0;
    double distance_mm = 0, depth_mm = 0, lateral_mm = 0;  // sums of the error's norms
    double growth_mm = 0;  // sum of the step's change of the 3D error (this point - previous)
    int over_5mm = 0;
    void Add(double distance_mm, double depth_mm, double growth_mm);
    void Print(const char* label) const;
  };
  static constexpr int kStepBins = 5, kViewBins = 3, kAngleBins = 4, kStartBins = 3;
  Bin by_step_[kStepBins];    // steps 1-2, 3-4, 5-8, 9-16, 17+
  Bin by_views_[kViewBins];   // views within support_px: <= 1, 2, 3+
  Bin by_angle_[kAngleBins];  // two views: < 15, 15-25, 25-45, 45-90 degrees
  Bin by_start_[kStartBins];  // start end off its cane < 2, 2-4, 4-10 mm
  Bin all_;
  int ends_ = 0, ends_off_ = 0;
  double start_mm_ = 0, start_depth_mm_ = 0;
  // Points held by exactly two views where a third sees it: how often the third view holds the
  // true point within support_px (it could have fixed the depth).
  int third_seen_ = 0, third_holds_truth_ = 0, third_holds_point_ = 0;
};

}  // namespace vb::reconstruct
