// SPDX-License-Identifier: Apache-2.0
// Simulated cameras: the renderer (sim/renderer.h) behind the Camera interface, looking at a
// SimWorld that cuts may change between captures. Each trigger renders the world as it is then.
// Not thread-safe (one capture worker drives the rig); the world must outlive the cameras and
// must not be mutated while a camera renders.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/calibration.h"
#include "sim/renderer.h"
#include "sim/world.h"
#include "workers/capture/camera.h"

namespace vb::capture {

class SimulatedCamera : public Camera {
 public:
  // `true_calibration` is where the camera really is (what it renders with); the calibration a
  // bundle reports may differ (sim::PerturbCalibration). `noise_seed` seeds the sensor noise of
  // the first frame; later frames use following seeds.
  SimulatedCamera(const sim::SimWorld* world, CameraCalibration true_calibration,
                  sim::RenderOptions base_options, uint64_t noise_seed);

  const std::string& name() const override { return calibration_.name; }
  absl::Status Open() override;
  // Exposure scales the rendered light linearly (4000 us is the renderer's nominal exposure 1.0);
  // gain multiplies it by 10^(dB/20). Hardware triggering is not simulated: INVALID_ARGUMENT.
  absl::Status Configure(const CameraSettings& settings) override;
  absl::Status StartAcquisition() override;
  absl::Status Trigger() override;
  // Returns the triggered frame; DEADLINE_EXCEEDED at once when nothing was triggered (nothing
  // else could arrive). In free-running mode renders a frame on demand.
  absl::StatusOr<Frame> Retrieve(absl::Duration timeout) override;
  absl::Status StopAcquisition() override;
  void Close() override;

  // Makes every later call fail with UNAVAILABLE, as a camera whose cable was pulled.
  void Disconnect() { disconnected_ = true; }

 private:
  absl::Status CheckUsable() const;
  absl::StatusOr<Frame> RenderFrame();

  const sim::SimWorld* world_;
  CameraCalibration calibration_;
  sim::RenderOptions options_;
  uint64_t next_seed_;
  CameraSettings settings_;
  bool open_ = false;
  bool acquiring_ = false;
  bool disconnected_ = false;
  uint64_t frame_id_ = 0;
  std::optional<Frame> pending_;
};

// One simulated camera per camera of `true_rig`, all looking at `world`.
std::vector<std::unique_ptr<Camera>> MakeSimulatedCameras(const sim::SimWorld* world,
                                                          const RigCalibration& true_rig,
                                                          const sim::RenderOptions& options,
                                                          uint64_t noise_seed);

}  // namespace vb::capture
