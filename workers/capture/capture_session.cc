// SPDX-License-Identifier: Apache-2.0
#include "workers/capture/capture_session.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"

namespace vb::capture {

absl::Status CaptureRequest::Validate() const {
  if (!std::isfinite(vine_position_m)) {
    return absl::InvalidArgumentError("vine_position_m: not finite");
  }
  if (timeout <= absl::ZeroDuration()) return absl::InvalidArgumentError("timeout: must be > 0");
  return settings.Validate();
}

namespace {

absl::Status Annotate(const std::string& camera, const absl::Status& s) {
  return absl::Status(s.code(), absl::StrCat("camera ", camera, ": ", std::string(s.message())));
}

// Stops acquisition on every camera when it goes out of scope, so no error path leaves a
// camera streaming.
class AcquisitionGuard {
 public:
  explicit AcquisitionGuard(std::span<Camera* const> cameras) : cameras_(cameras) {}
  ~AcquisitionGuard() {
    for (size_t i = 0; i < started_; ++i) (void)cameras_[i]->StopAcquisition();
  }
  absl::Status StartAll() {
    for (; started_ < cameras_.size(); ++started_) {
      Camera* c = cameras_[started_];
      if (absl::Status s = c->StartAcquisition(); !s.ok()) return Annotate(c->name(), s);
    }
    return absl::OkStatus();
  }

 private:
  std::span<Camera* const> cameras_;
  size_t started_ = 0;
};

}  // namespace

absl::StatusOr<CaptureBundle> CaptureStop(std::span<Camera* const> cameras,
                                          const RigCalibration& calibration,
                                          const CaptureRequest& request) {
  VB_RETURN_IF_ERROR(request.Validate());
  if (cameras.empty()) return absl::InvalidArgumentError("cameras: none given");
  CaptureBundle bundle;
  for (Camera* camera : cameras) {
    const auto index = calibration.IndexOf(camera->name());
    if (!index.has_value()) {
      return absl::InvalidArgumentError(
          absl::StrCat("calibration: no entry for camera '", camera->name(), "'"));
    }
    bundle.calibration.cameras.push_back(calibration.cameras[*index]);
    if (absl::Status s = camera->Configure(request.settings); !s.ok()) {
      return Annotate(camera->name(), s);
    }
  }
  std::vector<Frame> frames;
  {
    AcquisitionGuard guard(cameras);
    VB_RETURN_IF_ERROR(guard.StartAll());
    VB_ASSIGN_OR_RETURN(frames, GrabSynchronised(cameras, request.timeout));
  }
  bundle.metadata.row = request.row;
  bundle.metadata.vine_position_m = request.vine_position_m;
  bundle.metadata.captured_at = UtcNowIso8601();
  for (size_t i = 0; i < frames.size(); ++i) {
    const CameraCalibration& cal = bundle.calibration.cameras[i];
    const Image& image = frames[i].image;
    if (image.width != cal.image_width || image.height != cal.image_height) {
      return absl::InvalidArgumentError(absl::StrCat(
          "camera ", cal.name, ": delivered ", image.width, "x", image.height,
          " but calibration.yaml says ", cal.image_width, "x", cal.image_height));
    }
    bundle.metadata.cameras.push_back({cal.name, cal.name + ".png", image.format});
    bundle.images.push_back(std::move(frames[i].image));
  }
  return bundle;
}

}  // namespace vb::capture
