// SPDX-License-Identifier: Apache-2.0
#include "workers/capture/camera.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"

namespace vb::capture {
namespace {

// Generous sanity limits; each device narrows them further (AravisCamera checks its bounds).
constexpr double kMaxExposureUs = 10e6;  // 10 s
constexpr double kMaxGainDb = 60.0;

absl::Status Prefixed(const std::string& name, const absl::Status& status) {
  return absl::Status(status.code(), absl::StrCat(name, ": ", std::string(status.message())));
}

}  // namespace

absl::Status CameraSettings::Validate() const {
  if (!std::isfinite(exposure_us) || exposure_us <= 0.0 || exposure_us > kMaxExposureUs) {
    return absl::InvalidArgumentError(absl::StrCat(
        "exposure_us: ", exposure_us, " must be finite and in (0, ", kMaxExposureUs, "]"));
  }
  if (!std::isfinite(gain_db) || gain_db < 0.0 || gain_db > kMaxGainDb) {
    return absl::InvalidArgumentError(
        absl::StrCat("gain_db: ", gain_db, " must be finite and in [0, ", kMaxGainDb, "]"));
  }
  switch (pixel_format) {
    case PixelFormat::kRgb8:
    case PixelFormat::kMono8:
    case PixelFormat::kBayerRg8:
    case PixelFormat::kBayerGb8:
    case PixelFormat::kBayerGr8:
    case PixelFormat::kBayerBg8:
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrCat("pixel_format: unknown value ", static_cast<int>(pixel_format)));
  }
  switch (trigger) {
    case TriggerMode::kSoftware:
    case TriggerMode::kHardware:
    case TriggerMode::kFreeRunning:
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrCat("trigger: unknown value ", static_cast<int>(trigger)));
  }
  return absl::OkStatus();
}

absl::StatusOr<std::vector<Frame>> GrabSynchronised(std::span<Camera* const> cameras,
                                                    absl::Duration timeout) {
  if (cameras.empty()) return absl::InvalidArgumentError("cameras: empty");
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i] == nullptr) {
      return absl::InvalidArgumentError(absl::StrCat("cameras[", i, "]: null"));
    }
  }
  // One shared deadline: the rig's frames belong together, so the whole set must arrive in time.
  const absl::Time deadline = absl::Now() + timeout;
  for (Camera* camera : cameras) {
    if (absl::Status s = camera->Trigger(); !s.ok()) return Prefixed(camera->name(), s);
  }
  std::vector<Frame> frames;
  frames.reserve(cameras.size());
  for (Camera* camera : cameras) {
    const absl::Duration left = std::max(absl::ZeroDuration(), deadline - absl::Now());
    absl::StatusOr<Frame> frame = camera->Retrieve(left);
    if (!frame.ok()) return Prefixed(camera->name(), frame.status());
    if (frame->camera_name.empty()) frame->camera_name = camera->name();
    frames.push_back(*std::move(frame));
  }
  return frames;
}

}  // namespace vb::capture
