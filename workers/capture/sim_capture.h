// SPDX-License-Identifier: Apache-2.0
// A capture of a simulated stop with everything the simulator knows: the bundle (images rendered
// with the true rig, calibration.yaml as reported — with calibration error if asked), the ground
// truth vine model and a label image per camera. Thread-safe (no shared state).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/vine_model.h"
#include "sim/fiducials.h"
#include "sim/renderer.h"
#include "sim/rig.h"
#include "sim/scene.h"
#include "workers/capture/bundle.h"

namespace vb::capture {

struct SimCaptureOptions {
  sim::RigOptions rig;                // the simulated rig (true calibration)
  sim::RenderOptions render;          // pixel format, noise, lighting
  double calibration_error_px = 0.0;  // RMS reprojection error of the reported calibration
  std::string row = "sim";            // row name written to capture.json
  // The platform carries fiducials (sim/fiducials.h): the images show them and the calibration
  // lists their surveyed positions (exact: the survey has no error). On by default: they take
  // the rig's error after refinement from 0.89 to 0.28 px (docs/reconstruction.md, 3b).
  bool fiducials = true;
  sim::FiducialLayoutOptions fiducial_layout;

  absl::Status Validate() const;
};

// The simulated rig: where its cameras really are, and the calibration it reports (with
// options.calibration_error_px of error, deterministic in `noise_seed`), both listing the
// platform's fiducials when options.fiducials.
struct SimRig {
  RigCalibration true_rig;
  RigCalibration reported;
};
absl::StatusOr<SimRig> MakeSimRig(const SimCaptureOptions& options, uint64_t noise_seed);

struct SimCapture {
  CaptureBundle bundle;
  VineModel ground_truth;
  std::vector<LabelImage> labels;  // one per bundle camera, same order
};

// Renders `scene` through the rig of `options` (with the platform's fiducials on the backdrop when
// options.fiducials and the scene has none of its own). Deterministic in (scene, options, noise_seed).
absl::StatusOr<SimCapture> RenderSimCapture(const sim::Scene& scene, const SimCaptureOptions& options,
                                            uint64_t noise_seed);

// Writes the bundle to `dir` plus ground_truth.json and labels_<camera>.png (16-bit).
absl::Status WriteSimCapture(const std::string& dir, const SimCapture& capture);

}  // namespace vb::capture
