// SPDX-License-Identifier: Apache-2.0
#include "workers/capture/sim_camera.h"

#include <chrono>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace vb::capture {
namespace {

constexpr double kNominalExposureUs = 4000.0;

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

SimulatedCamera::SimulatedCamera(const sim::SimWorld* world, CameraCalibration true_calibration,
                                 sim::RenderOptions base_options, uint64_t noise_seed)
    : world_(world),
      calibration_(std::move(true_calibration)),
      options_(base_options),
      next_seed_(noise_seed) {
  settings_.pixel_format = options_.pixel_format;
}

absl::Status SimulatedCamera::CheckUsable() const {
  if (disconnected_) {
    return absl::UnavailableError(absl::StrCat("camera ", calibration_.name, ": disconnected"));
  }
  if (!open_) {
    return absl::FailedPreconditionError(absl::StrCat("camera ", calibration_.name, ": not open"));
  }
  return absl::OkStatus();
}

absl::Status SimulatedCamera::Open() {
  if (disconnected_) return CheckUsable();
  if (world_ == nullptr) {
    return absl::FailedPreconditionError(absl::StrCat("camera ", calibration_.name, ": no world"));
  }
  if (absl::Status s = calibration_.Validate(); !s.ok()) return s;
  open_ = true;
  return absl::OkStatus();
}

absl::Status SimulatedCamera::Configure(const CameraSettings& settings) {
  if (absl::Status s = CheckUsable(); !s.ok()) return s;
  if (acquiring_) {
    return absl::FailedPreconditionError(
        absl::StrCat("camera ", calibration_.name, ": cannot configure while acquiring"));
  }
  if (absl::Status s = settings.Validate(); !s.ok()) return s;
  if (settings.trigger == TriggerMode::kHardware) {
    return absl::InvalidArgumentError(absl::StrCat(
        "camera ", calibration_.name, ": trigger: hardware triggering is not simulated"));
  }
  settings_ = settings;
  options_.pixel_format = settings.pixel_format;
  options_.exposure = settings.exposure_us / kNominalExposureUs * std::pow(10.0, settings.gain_db / 20.0);
  return absl::OkStatus();
}

absl::Status SimulatedCamera::StartAcquisition() {
  if (absl::Status s = CheckUsable(); !s.ok()) return s;
  acquiring_ = true;
  pending_.reset();
  return absl::OkStatus();
}

absl::StatusOr<Frame> SimulatedCamera::RenderFrame() {
  auto view = sim::Render(world_->scene(), calibration_, options_, next_seed_++);
  if (!view.ok()) return view.status();
  Frame frame;
  frame.camera_name = calibration_.name;
  frame.image = std::move(view->image);
  frame.timestamp_ns = NowNs();
  frame.frame_id = ++frame_id_;
  return frame;
}

absl::Status SimulatedCamera::Trigger() {
  if (absl::Status s = CheckUsable(); !s.ok()) return s;
  if (!acquiring_) {
    return absl::FailedPreconditionError(
        absl::StrCat("camera ", calibration_.name, ": trigger while not acquiring"));
  }
  if (settings_.trigger != TriggerMode::kSoftware) return absl::OkStatus();
  auto frame = RenderFrame();
  if (!frame.ok()) return frame.status();
  pending_ = std::move(*frame);
  return absl::OkStatus();
}

absl::StatusOr<Frame> SimulatedCamera::Retrieve(absl::Duration /*timeout*/) {
  if (absl::Status s = CheckUsable(); !s.ok()) return s;
  if (!acquiring_) {
    return absl::FailedPreconditionError(
        absl::StrCat("camera ", calibration_.name, ": retrieve while not acquiring"));
  }
  if (settings_.trigger == TriggerMode::kFreeRunning) return RenderFrame();
  if (!pending_.has_value()) {
    return absl::DeadlineExceededError(
        absl::StrCat("camera ", calibration_.name, ": no frame (not triggered)"));
  }
  Frame frame = std::move(*pending_);
  pending_.reset();
  return frame;
}

absl::Status SimulatedCamera::StopAcquisition() {
  if (absl::Status s = CheckUsable(); !s.ok()) return s;
  acquiring_ = false;
  pending_.reset();
  return absl::OkStatus();
}

void SimulatedCamera::Close() {
  acquiring_ = false;
  open_ = false;
  pending_.reset();
}

std::vector<std::unique_ptr<Camera>> MakeSimulatedCameras(const sim::SimWorld* world,
                                                          const RigCalibration& true_rig,
                                                          const sim::RenderOptions& options,
                                                          uint64_t noise_seed) {
  std::vector<std::unique_ptr<Camera>> cameras;
  for (size_t i = 0; i < true_rig.cameras.size(); ++i) {
    // Seeds far apart so the cameras' noise sequences never overlap.
    cameras.push_back(std::make_unique<SimulatedCamera>(world, true_rig.cameras[i], options,
                                                        noise_seed + (i + 1) * 0x9E3779B97F4A7C15ull));
  }
  return cameras;
}

}  // namespace vb::capture
