// SPDX-License-Identifier: Apache-2.0
#include <iostream>
#include <memory>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "app/commands.h"
#include "app/sim_flags.h"
#include "core/status_macros.h"
#include "core/vine_model_json.h"
#include "sim/vine_generator.h"
#include "sim/world.h"
#include "workers/capture/aravis_camera.h"
#include "workers/capture/capture_session.h"
#include "workers/capture/sim_camera.h"
#include "workers/capture/sim_capture.h"

namespace vb::app {
namespace {

absl::StatusOr<capture::TriggerMode> ParseTrigger(const std::string& name) {
  if (name == "software") return capture::TriggerMode::kSoftware;
  if (name == "hardware") return capture::TriggerMode::kHardware;
  if (name == "free") return capture::TriggerMode::kFreeRunning;
  return absl::InvalidArgumentError(
      absl::StrCat("--trigger: unknown '", name, "' (expected software, hardware or free)"));
}

// Flags common to both sources: camera settings, timeout, row position.
absl::StatusOr<capture::CaptureRequest> ReadRequest(Flags& flags, const std::string& row_default) {
  capture::CaptureRequest request;
  VB_ASSIGN_OR_RETURN(request.row, flags.String("row", row_default));
  VB_ASSIGN_OR_RETURN(request.vine_position_m, flags.Double("position-m", 0.0));
  VB_ASSIGN_OR_RETURN(request.settings.exposure_us, flags.Double("exposure-us", 4000.0));
  VB_ASSIGN_OR_RETURN(request.settings.gain_db, flags.Double("gain-db", 0.0));
  VB_ASSIGN_OR_RETURN(const std::string trigger, flags.String("trigger", "software"));
  VB_ASSIGN_OR_RETURN(request.settings.trigger, ParseTrigger(trigger));
  VB_ASSIGN_OR_RETURN(const double timeout_s, flags.Double("timeout-s", 3.0));
  request.timeout = absl::Seconds(timeout_s);
  return request;
}

absl::Status CaptureFromSimulator(Flags& flags, const std::string& out) {
  VB_ASSIGN_OR_RETURN(SimStopFlags stop, ReadSimStopFlags(flags));
  VB_ASSIGN_OR_RETURN(capture::CaptureRequest request, ReadRequest(flags, stop.capture.row));
  request.settings.pixel_format = stop.capture.render.pixel_format;
  VB_RETURN_IF_ERROR(flags.Finish());

  VB_ASSIGN_OR_RETURN(sim::Scene scene, sim::GenerateScene(stop.seed, stop.vine, stop.generator));
  if (!flags.Has("position-m")) request.vine_position_m = scene.vine_position_m;
  VB_ASSIGN_OR_RETURN(const capture::SimRig sim_rig, capture::MakeSimRig(stop.capture, stop.noise_seed));
  scene.fiducials = sim_rig.true_rig.fiducials;  // the platform's, drawn on the backdrop
  sim::SimWorld world(std::move(scene));
  std::vector<std::unique_ptr<capture::Camera>> cameras =
      capture::MakeSimulatedCameras(&world, sim_rig.true_rig, stop.capture.render, stop.noise_seed);
  std::vector<capture::Camera*> rig;
  for (auto& c : cameras) {
    VB_RETURN_IF_ERROR(c->Open());
    rig.push_back(c.get());
  }
  VB_ASSIGN_OR_RETURN(const capture::CaptureBundle bundle,
                      capture::CaptureStop(rig, sim_rig.reported, request));
  for (auto& c : cameras) c->Close();
  VB_RETURN_IF_ERROR(capture::WriteBundle(out, bundle));
  VB_RETURN_IF_ERROR(WriteVineModel(out + "/ground_truth.json", world.scene().vine));
  std::cout << absl::StrCat("captured ", bundle.images.size(), " simulated cameras to ", out, "\n");
  return absl::OkStatus();
}

// --devices cam0=127.0.0.1,cam1=127.0.0.2: rig camera name = Aravis device id or address.
absl::Status CaptureFromAravis(Flags& flags, const std::string& out) {
  VB_ASSIGN_OR_RETURN(const std::string devices, flags.RequiredString("devices"));
  VB_ASSIGN_OR_RETURN(const std::string calibration_path, flags.RequiredString("calibration"));
  VB_ASSIGN_OR_RETURN(capture::CaptureRequest request, ReadRequest(flags, "row"));
  VB_ASSIGN_OR_RETURN(request.settings.pixel_format, flags.Format("pixel-format", PixelFormat::kRgb8));
  VB_RETURN_IF_ERROR(flags.Finish());

  VB_ASSIGN_OR_RETURN(const RigCalibration calibration,
                      capture::ReadCalibrationYaml(calibration_path));
  std::vector<std::unique_ptr<capture::Camera>> cameras;
  for (const std::string& entry : std::vector<std::string>(absl::StrSplit(devices, ',', absl::SkipEmpty()))) {
    const std::vector<std::string> parts = absl::StrSplit(entry, absl::MaxSplits('=', 1));
    if (parts.size() != 2 || parts[0].empty() || parts[1].empty()) {
      return absl::InvalidArgumentError(
          absl::StrCat("--devices: '", entry, "' is not NAME=DEVICE (e.g. cam0=192.168.1.20)"));
    }
    cameras.push_back(capture::MakeAravisCamera(parts[0], parts[1]));
  }
  std::vector<capture::Camera*> rig;
  for (auto& c : cameras) {
    if (absl::Status s = c->Open(); !s.ok()) {
      return absl::Status(s.code(), absl::StrCat("camera ", c->name(), ": ", std::string(s.message())));
    }
    rig.push_back(c.get());
  }
  auto bundle = capture::CaptureStop(rig, calibration, request);
  for (auto& c : cameras) c->Close();
  if (!bundle.ok()) return bundle.status();
  VB_RETURN_IF_ERROR(capture::WriteBundle(out, *bundle));
  std::cout << absl::StrCat("captured ", bundle->images.size(), " cameras to ", out, "\n");
  return absl::OkStatus();
}

}  // namespace

absl::Status RunCapture(Flags& flags) {
  VB_ASSIGN_OR_RETURN(const std::string source, flags.RequiredString("source"));
  VB_ASSIGN_OR_RETURN(const std::string out, flags.RequiredString("out"));
  if (source == "sim") return CaptureFromSimulator(flags, out);
  if (source == "aravis") return CaptureFromAravis(flags, out);
  return absl::InvalidArgumentError(
      absl::StrCat("--source: unknown '", source, "' (expected sim or aravis)"));
}

}  // namespace vb::app
