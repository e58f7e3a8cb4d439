// SPDX-License-Identifier: Apache-2.0
#include "workers/capture/sim_capture.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"
#include "core/vine_model_json.h"

namespace vb::capture {

absl::Status SimCaptureOptions::Validate() const {
  VB_RETURN_IF_ERROR(rig.Validate());
  VB_RETURN_IF_ERROR(render.Validate());
  if (fiducials) VB_RETURN_IF_ERROR(fiducial_layout.Validate());
  if (!std::isfinite(calibration_error_px) || calibration_error_px < 0.0) {
    return absl::InvalidArgumentError("calibration_error_px: must be finite and >= 0");
  }
  return absl::OkStatus();
}

absl::StatusOr<SimRig> MakeSimRig(const SimCaptureOptions& options, uint64_t noise_seed) {
  VB_RETURN_IF_ERROR(options.Validate());
  SimRig rig;
  VB_ASSIGN_OR_RETURN(rig.true_rig, sim::MakeRig(options.rig));
  if (options.fiducials) {
    VB_ASSIGN_OR_RETURN(rig.true_rig.fiducials, sim::PlatformFiducials(options.fiducial_layout));
  }
  rig.reported =
      sim::PerturbCalibration(rig.true_rig, options.calibration_error_px, noise_seed ^ 0xCA11B4A7Eull);
  return rig;
}

absl::StatusOr<SimCapture> RenderSimCapture(const sim::Scene& scene, const SimCaptureOptions& options,
                                            uint64_t noise_seed) {
  VB_ASSIGN_OR_RETURN(SimRig rig, MakeSimRig(options, noise_seed));
  const RigCalibration& true_rig = rig.true_rig;
  const sim::Scene* drawn = &scene;
  sim::Scene with_fiducials;
  if (!true_rig.fiducials.empty() && scene.fiducials.empty()) {
    with_fiducials = scene;
    with_fiducials.fiducials = true_rig.fiducials;
    drawn = &with_fiducials;
  }
  SimCapture capture;
  capture.ground_truth = scene.vine;
  capture.bundle.calibration = std::move(rig.reported);
  capture.bundle.metadata.row = options.row;
  capture.bundle.metadata.vine_position_m = scene.vine_position_m;
  capture.bundle.metadata.captured_at = UtcNowIso8601();
  for (size_t i = 0; i < true_rig.cameras.size(); ++i) {
    const CameraCalibration& camera = true_rig.cameras[i];
    VB_ASSIGN_OR_RETURN(sim::RenderedView view,
                        sim::Render(*drawn, camera, options.render, noise_seed + 7919 * (i + 1)));
    capture.bundle.metadata.cameras.push_back(
        {camera.name, camera.name + ".png", options.render.pixel_format});
    capture.bundle.images.push_back(std::move(view.image));
    capture.labels.push_back(std::move(view.labels));
  }
  return capture;
}

absl::Status WriteSimCapture(const std::string& dir, const SimCapture& capture) {
  VB_RETURN_IF_ERROR(WriteBundle(dir, capture.bundle));
  VB_RETURN_IF_ERROR(WriteVineModel(dir + "/ground_truth.json", capture.ground_truth));
  for (size_t i = 0; i < capture.labels.size(); ++i) {
    VB_RETURN_IF_ERROR(WriteLabelPng(
        absl::StrCat(dir, "/labels_", capture.bundle.metadata.cameras[i].name, ".png"),
        capture.labels[i]));
  }
  return absl::OkStatus();
}

}  // namespace vb::capture
