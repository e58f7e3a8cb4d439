// SPDX-License-Identifier: Apache-2.0
// The camera interface of the capture stage, with a real implementation (Aravis: GigE Vision and
// USB3 Vision) and a simulated one (the renderer). Every failure is a Status, never an abort.
//
// Life cycle: Open -> Configure -> StartAcquisition -> (Trigger, Retrieve)* -> StopAcquisition
// -> Close. Configure is only allowed while not acquiring. A Camera is not thread-safe: one
// thread (the capture worker) drives it.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "core/image.h"

namespace vb::capture {

enum class TriggerMode {
  kSoftware,    // frames are taken on Trigger(); the rig is synchronised by triggering all at once
  kHardware,    // frames are taken on an external trigger line (Line1) wired to every camera
  kFreeRunning  // continuous; Retrieve returns the next frame
};

struct CameraSettings {
  double exposure_us = 4000.0;  // exposure time, microseconds (> 0)
  double gain_db = 0.0;         // analogue gain, dB (>= 0)
  PixelFormat pixel_format = PixelFormat::kRgb8;
  TriggerMode trigger = TriggerMode::kSoftware;

  // INVALID_ARGUMENT naming the field for non-finite or out-of-range values.
  absl::Status Validate() const;
};

struct Frame {
  std::string camera_name;
  Image image;
  int64_t timestamp_ns = 0;  // camera (or simulated) timestamp of the exposure
  uint64_t frame_id = 0;     // increasing per camera
};

class Camera {
 public:
  virtual ~Camera() = default;

  // The rig name of this camera (matches the calibration, e.g. "cam0").
  virtual const std::string& name() const = 0;

  // Connects to the device. UNAVAILABLE if it cannot be reached; NOT_FOUND if no such device.
  virtual absl::Status Open() = 0;
  // Applies settings. INVALID_ARGUMENT (naming the setting) if the device rejects a value or a
  // pixel format it does not support; FAILED_PRECONDITION if not open or acquiring.
  virtual absl::Status Configure(const CameraSettings& settings) = 0;
  virtual absl::Status StartAcquisition() = 0;
  // Requests one exposure (software trigger mode; a no-op otherwise).
  virtual absl::Status Trigger() = 0;
  // Waits for the next frame. DEADLINE_EXCEEDED on timeout; UNAVAILABLE if the device vanished;
  // DATA_LOSS for an incomplete frame.
  virtual absl::StatusOr<Frame> Retrieve(absl::Duration timeout) = 0;
  virtual absl::Status StopAcquisition() = 0;
  // Releases the device; safe to call in any state, more than once.
  virtual void Close() = 0;
};

// Grabs one synchronised set: triggers every camera back to back, then retrieves one frame from
// each within `timeout`. Frames come back in the order of `cameras`. Fails with the first error
// (prefixed by the camera name); DEADLINE_EXCEEDED if a camera does not deliver in time.
// INVALID_ARGUMENT for an empty list or a null camera. After a failure, frames of cameras that
// were already triggered may still be queued; restart acquisition before the next set.
absl::StatusOr<std::vector<Frame>> GrabSynchronised(std::span<Camera* const> cameras,
                                                    absl::Duration timeout);

}  // namespace vb::capture
