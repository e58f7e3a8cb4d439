// SPDX-License-Identifier: Apache-2.0
// One stop's capture: configure the rig, grab a synchronised set, and assemble a capture bundle
// with the rig's calibration. The cameras must be open; they are left open and not acquiring.
// Not thread-safe (drives the cameras).
#pragma once

#include <span>
#include <string>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "core/calibration.h"
#include "workers/capture/bundle.h"
#include "workers/capture/camera.h"

namespace vb::capture {

struct CaptureRequest {
  std::string row = "row";                  // vineyard row name written to capture.json
  double vine_position_m = 0.0;             // platform position along the row
  CameraSettings settings;                  // applied to every camera
  absl::Duration timeout = absl::Seconds(3);  // for the whole synchronised grab

  // INVALID_ARGUMENT naming the field (settings.*, vine_position_m, timeout).
  absl::Status Validate() const;
};

// Captures one synchronised set from `cameras` and returns it as a bundle whose calibration holds
// each camera's entry from `calibration` (by camera name) and images named "<camera>.png".
// INVALID_ARGUMENT if a camera has no calibration or delivers an image whose size disagrees
// with it; otherwise the first camera error (prefixed with the camera name). Acquisition is
// stopped on every path.
absl::StatusOr<CaptureBundle> CaptureStop(std::span<Camera* const> cameras,
                                          const RigCalibration& calibration,
                                          const CaptureRequest& request);

}  // namespace vb::capture
