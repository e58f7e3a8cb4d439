// SPDX-License-Identifier: Apache-2.0
// Real cameras through Aravis 0.8 (GigE Vision and USB3 Vision, GenICam SFNC features). The
// Aravis/GLib types stay in aravis_camera.cc (PIMPL) so this header is light.
//
// Mapping of the Camera contract onto GenICam:
//   Open              arv_camera_new(device_id): an IP address ("192.168.10.11") or a device id
//                     ("Basler-21712345", as listed by arv-tool-0.8). NOT_FOUND if no such
//                     device answers, UNAVAILABLE for other connection failures; both name the
//                     device. Takes GigE Vision control (exclusive) of the device.
//   Configure         PixelFormat (PFNC names RGB8 / Mono8 / BayerRG8 / BayerGB8 / BayerGR8 /
//                     BayerBG8; checked against the device's available entries first),
//                     ExposureTime[Abs] (checked against the device's bounds), Gain (checked
//                     against its bounds), AcquisitionMode Continuous, and the trigger:
//                       kSoftware:    TriggerSelector FrameStart, TriggerMode On, source Software
//                       kHardware:    same with source AravisCameraOptions::hardware_trigger_source
//                       kFreeRunning: all triggers off
//                     INVALID_ARGUMENT naming the CameraSettings field (pixel_format, exposure_us,
//                     gain_db, trigger) when the device lacks the value; FAILED_PRECONDITION when
//                     not open or while acquiring.
//   StartAcquisition  creates the stream, queues options.n_buffers buffers of PayloadSize, and
//                     starts. FAILED_PRECONDITION unless open, configured and not acquiring.
//   Trigger           TriggerSoftware in kSoftware mode, else a no-op.
//   Retrieve          pops the next buffer; the image is copied out and the buffer re-queued.
//                     DEADLINE_EXCEEDED on timeout; DATA_LOSS (naming the Aravis buffer status)
//                     for an incomplete frame; UNAVAILABLE once the device stopped answering.
//                     timestamp_ns is the device timestamp (GVSP leader), or the host reception
//                     time if the device reports none; frame_id is the GVSP block id.
//   Close             stops acquisition if needed and releases the device; idempotent.
//
// A vanished device (unplugged, powered off, process killed) is detected when a control command
// times out (Aravis: 500 ms x 5 retries, not configurable in 0.8.26, so ~2.5 s for the first
// failing Trigger/Configure) or when Aravis' heartbeat thread reports lost control; from then on
// every call fails fast with UNAVAILABLE and Close skips the control traffic it can skip. A pure
// stream loss with a live control channel shows as DEADLINE_EXCEEDED from Retrieve.
// Releasing a vanished device still blocks: Aravis' stream and device finalizers each send GVCP
// commands that time out (measured ~5 s in StopAcquisition and ~5 s more in Close against the
// killed fake). This is deliberately synchronous: releasing in the background could let the stale
// "leave control" reach the same camera after it came back and was reopened.
//
// Verified ONLY against Aravis' fake GigE Vision camera (arv-fake-gv-camera-0.8, aravis-tools
// 0.8.26) on loopback — not yet against a real camera:
//   - the six pixel formats (the fake also offers Mono16, which vinebot does not accept), 512x512
//     by default, RGB8 delivered as 3 bytes per pixel;
//   - exposure via ExposureTimeAbs, bounds [10, 1e7] us;
//   - gain: the fake has no "Gain" (dB) feature, only an integer "GainRaw" in [0, 10] which
//     arv_camera_set_gain writes instead — on such devices gain_db is really in device units;
//   - trigger sources Software and Line0 only (no Line1): kHardware with the default Line1 is
//     rejected (INVALID_ARGUMENT naming trigger) by the fake; with "Line0" it configures, but no
//     hardware trigger ever arrives;
//   - software trigger and free running; frame ids and device timestamps increasing per frame;
//   - vanishing device: the fake process killed mid-stream; lossy stream (fake -r 500) -> DATA_LOSS.
// Not verified: USB3 Vision, packet loss/resend on a real network, Bayer colour layout of real
// sensors, cameras whose exposure feature is not in microseconds, chunk data, multipart buffers.
//
// Thread safety: as Camera — one thread drives an AravisCamera. Aravis' own stream and heartbeat
// threads run inside; they only touch state guarded by Aravis or atomics.
#pragma once

#include <memory>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "workers/capture/camera.h"

namespace vb::capture {

struct AravisCameraOptions {
  // TriggerSource used in TriggerMode::kHardware (the rig wires one line to every camera).
  std::string hardware_trigger_source = "Line1";
  // Stream buffers of PayloadSize queued at StartAcquisition (>= 1).
  int n_buffers = 4;

  // INVALID_ARGUMENT naming the field.
  absl::Status Validate() const;
};

class AravisCamera final : public Camera {
 public:
  // `rig_name` is the calibration name ("cam0"); `device_id` is what arv_camera_new accepts.
  // Nothing is contacted until Open().
  AravisCamera(std::string rig_name, std::string device_id, AravisCameraOptions options = {});
  ~AravisCamera() override;  // Close()s
  AravisCamera(const AravisCamera&) = delete;
  AravisCamera& operator=(const AravisCamera&) = delete;

  const std::string& name() const override { return name_; }
  const std::string& device_id() const { return device_id_; }

  absl::Status Open() override;
  absl::Status Configure(const CameraSettings& settings) override;
  absl::Status StartAcquisition() override;
  absl::Status Trigger() override;
  absl::StatusOr<Frame> Retrieve(absl::Duration timeout) override;
  absl::Status StopAcquisition() override;
  void Close() override;

 private:
  struct Impl;
  std::string name_;
  std::string device_id_;
  std::unique_ptr<Impl> impl_;
};

std::unique_ptr<Camera> MakeAravisCamera(std::string rig_name, std::string device_id,
                                         AravisCameraOptions options = {});

}  // namespace vb::capture
