// SPDX-License-Identifier: Apache-2.0
// What a rig can see of a vine at all: the share of the true trunk + cane length that lies inside
// two or more of the rig's images (the least stereo needs), one, or none. Occlusion and
// segmentation are not considered: this is the ceiling the field of view puts on cane recall
// (core/model_metrics.h), whatever the reconstruction does. A sample is "inside" a camera's image
// when it projects (in front of the camera, within the lens model's invertible region,
// CameraCalibration::Project) onto a pixel of the image (CameraCalibration::InImage).
// Thread-safe (pure functions).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/vine_model.h"
#include "nlohmann/json.hpp"

namespace vb {

// Where a sample lies with respect to one camera's image.
enum class ImageSide : uint8_t {
  kInside,
  kBeyondLeft,    // u < 0 (toward -x for the default rig)
  kBeyondRight,   // u >= width
  kBeyondTop,     // v < 0 (up)
  kBeyondBottom,  // v >= height (down)
  kNotProjected,  // behind the camera or beyond the fold of the lens model
};

// One sample of the true trunk + canes (kinds trunk and cane, as cane_recall counts them).
struct CoverageSample {
  Eigen::Vector3d point;         // platform frame
  double length_m = 0.0;         // the length of polyline it stands for
  CaneKind kind = CaneKind::kCane;
  int cane_index = 0;            // index into VineModel::canes
  std::vector<ImageSide> sides;  // one per rig camera, in rig order
  int views = 0;                 // number of cameras whose image it lies inside
};

// Samples every `sample_step_m` (as the recall metric does) along every trunk and cane of
// `truth` and classifies each against every camera of `rig`. Beyond the image, the side is the
// border exceeded most (in pixels, through the lens model where it is invertible, else through
// the pinhole direction). INVALID_ARGUMENT naming "truth", "rig" or "sample_step_m" if the model
// or rig fails Validate or the step is not positive and finite.
absl::StatusOr<std::vector<CoverageSample>> SampleViewCoverage(const VineModel& truth,
                                                               const RigCalibration& rig,
                                                               double sample_step_m = 0.005);

struct ViewCoverage {
  double truth_cane_length_m = 0.0;  // trunk + canes, the recall denominator
  // Shares of that length inside >= 2, exactly 1 and 0 of the images (they sum to 1; all 0 when
  // the truth has no trunk or cane).
  double in_two_or_more_fraction = 0.0;
  double in_one_fraction = 0.0;
  double in_none_fraction = 0.0;
  // Share of the length that is trunk and inside fewer than two images.
  double trunk_in_fewer_than_two_fraction = 0.0;
  // Per camera (rig order): share of the length outside that camera's image, by side. Indexed by
  // ImageSide (kInside holds the share inside).
  std::vector<std::array<double, 6>> side_fraction;
};

ViewCoverage SummariseViewCoverage(const std::vector<CoverageSample>& samples, int camera_count);

// SampleViewCoverage + SummariseViewCoverage.
absl::StatusOr<ViewCoverage> EvaluateViewCoverage(const VineModel& truth, const RigCalibration& rig,
                                                  double sample_step_m = 0.005);

// {"cane_length_in_two_views_fraction": ..., "cane_length_in_one_view_fraction": ...,
//  "cane_length_in_no_view_fraction": ..., "trunk_length_in_fewer_than_two_views_fraction": ...}
nlohmann::json ViewCoverageToJson(const ViewCoverage& coverage);

}  // namespace vb
