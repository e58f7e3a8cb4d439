// SPDX-License-Identifier: Apache-2.0
// Finds the platform's fiducials (core/calibration.h: white discs printed on the backdrop at
// surveyed positions) in one camera's image, to sub-pixel precision. Each fiducial is looked for
// only near where the calibration projects it (search_radius_px): association is by position,
// so the discs need no code. In a window around that point the disc is the connected bright
// region (min of R, G, B above half-way between the window's median and its brightest 3x3 mean)
// whose area matches the disc's projected area; its centre is the centroid of the brightness
// above the median over that region grown by 2 px. A disc that is faint, of the wrong size, or
// whose surround is not clean backdrop (a cane, wire or post across or beside it: a partly hidden
// disc would give a biased centre) is reported missing with the reason. Discs are assumed to
// face the cameras along -y (printed on the backdrop, a plane y = const).
// Thread-safe (pure function).
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/calibration.h"
#include "core/image.h"
#include "Eigen/Core"
#include "workers/reconstruct/view2d.h"

namespace vb::reconstruct {

struct FiducialDetectOptions {
  bool enabled = true;             // false: not looked for (the rig is refined as without them)
  double search_radius_px = 20.0;  // how far from its calibrated projection a disc is looked for
  double min_contrast_dn = 30.0;   // disc minus surround, in min(R, G, B) digital numbers
  double area_tolerance = 0.45;    // accepted area: expected x [1 - tol, 1 + tol]
  double min_radius_px = 2.5;      // a disc smaller than this in the image is not looked for
  double min_clean_surround = 0.9; // fraction of the ring 1.6-2.4 radii out that must be backdrop
  // The centres of the bright region and of the white one further apart than this: the disc is
  // half in a shadow or partly hidden, and is not used.
  double max_centre_disagreement_px = 0.3;

  // INVALID_ARGUMENT naming the field for a non-finite or out-of-range value.
  absl::Status Validate() const;
};

struct FiducialDetectSummary {
  int looked_for = 0;               // fiducials projecting into the image
  int found = 0;
  std::vector<std::string> missed;  // "<name>: <reason>" for each one looked for but not found
};

// The fiducials of `fiducials` seen in `image` (rgb8, taken by `camera`). INVALID_ARGUMENT for
// invalid options, a non-rgb8 image or one whose size differs from the camera's.
absl::StatusOr<std::vector<FiducialObservation>> DetectFiducials(
    const Image& image, const CameraCalibration& camera, const std::vector<Fiducial>& fiducials,
    const FiducialDetectOptions& options, FiducialDetectSummary* summary = nullptr);

// Sets to background the pixels of `classes` within 1.5 disc radii of each found fiducial: the
// segmenter (trained on images without discs) takes most of a white disc for wood, and a found
// disc's surround is clean backdrop (out to 2.4 radii), so nothing else is lost.
void ClearFiducials(const std::vector<FiducialObservation>& found, const CameraCalibration& camera,
                    const std::vector<Fiducial>& fiducials, ClassImage* classes);

}  // namespace vb::reconstruct
