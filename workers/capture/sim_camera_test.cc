// SPDX-License-Identifier: Apache-2.0
#include "workers/capture/sim_camera.h"

#include <memory>
#include <vector>

#include "gtest/gtest.h"
#include "sim/rig.h"
#include "sim/vine_generator.h"
#include "sim/world.h"
#include "workers/capture/capture_session.h"

namespace vb::capture {
namespace {

class SimulatedCameraTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto scene = sim::GenerateScene(11, 2);
    ASSERT_TRUE(scene.ok()) << scene.status();
    world_ = std::make_unique<sim::SimWorld>(std::move(*scene));
    sim::RigOptions rig_options;
    rig_options.image_width = 320;  // small images keep the test fast
    rig_options.image_height = 256;
    auto rig = sim::MakeRig(rig_options);
    ASSERT_TRUE(rig.ok()) << rig.status();
    rig_ = *rig;
    cameras_ = MakeSimulatedCameras(world_.get(), rig_, sim::RenderOptions{}, 42);
    for (auto& c : cameras_) {
      ASSERT_TRUE(c->Open().ok());
      pointers_.push_back(c.get());
    }
  }

  // Number of pixels differing between two images.
  static int DifferingPixels(const Image& a, const Image& b) {
    int n = 0;
    for (size_t i = 0; i < a.data.size(); ++i) n += a.data[i] != b.data[i];
    return n;
  }

  std::unique_ptr<sim::SimWorld> world_;
  RigCalibration rig_;
  std::vector<std::unique_ptr<Camera>> cameras_;
  std::vector<Camera*> pointers_;
};

TEST_F(SimulatedCameraTest, CaptureStopGrabsASynchronisedBundle) {
  CaptureRequest request;
  request.row = "r1";
  request.settings.pixel_format = PixelFormat::kBayerBg8;
  auto bundle = CaptureStop(pointers_, rig_, request);
  ASSERT_TRUE(bundle.ok()) << bundle.status();
  ASSERT_EQ(bundle->images.size(), 3u);
  EXPECT_EQ(bundle->metadata.cameras[2].name, "cam2");
  EXPECT_EQ(bundle->metadata.cameras[2].image, "cam2.png");
  EXPECT_EQ(bundle->images[0].format, PixelFormat::kBayerBg8);
  EXPECT_EQ(bundle->images[0].width, 320);
  EXPECT_EQ(bundle->calibration.cameras.size(), 3u);
}

TEST_F(SimulatedCameraTest, ReCaptureShowsACut) {
  CaptureRequest request;
  request.settings.exposure_us = 4000;
  auto before = CaptureStop(pointers_, rig_, request);
  ASSERT_TRUE(before.ok());
  // Cut the longest cane near its base: a large part of the image must change.
  const VineModel& vine = world_->scene().vine;
  const Cane* longest = nullptr;
  for (const Cane& c : vine.canes) {
    if (c.kind == CaneKind::kCane && (longest == nullptr || c.polyline.Length() > longest->polyline.Length())) {
      longest = &c;
    }
  }
  ASSERT_NE(longest, nullptr);
  const CaneId id = longest->id;
  const Eigen::Vector3d point = longest->polyline.PointAt(0.02);
  ASSERT_TRUE(world_->ApplyCut(id, point).ok());
  auto after = CaptureStop(pointers_, rig_, request);
  ASSERT_TRUE(after.ok());
  int changed = 0;
  for (size_t i = 0; i < 3; ++i) changed += DifferingPixels(before->images[i], after->images[i]);
  // Noise differs between frames too; compare against two frames of the uncut world.
  auto again = CaptureStop(pointers_, rig_, request);
  ASSERT_TRUE(again.ok());
  int noise_only = 0;
  for (size_t i = 0; i < 3; ++i) noise_only += DifferingPixels(after->images[i], again->images[i]);
  EXPECT_GT(changed, noise_only);
}

TEST_F(SimulatedCameraTest, ExposureScalesBrightness) {
  CaptureRequest dark;
  dark.settings.exposure_us = 1000;
  CaptureRequest bright;
  bright.settings.exposure_us = 6000;
  auto a = CaptureStop(pointers_, rig_, dark);
  auto b = CaptureStop(pointers_, rig_, bright);
  ASSERT_TRUE(a.ok() && b.ok());
  double sum_a = 0, sum_b = 0;
  for (uint8_t v : a->images[0].data) sum_a += v;
  for (uint8_t v : b->images[0].data) sum_b += v;
  EXPECT_GT(sum_b, 2.0 * sum_a);
}

TEST_F(SimulatedCameraTest, RetrieveWithoutTriggerTimesOut) {
  Camera& cam = *cameras_[0];
  ASSERT_TRUE(cam.Configure(CameraSettings{}).ok());
  ASSERT_TRUE(cam.StartAcquisition().ok());
  EXPECT_EQ(cam.Retrieve(absl::Milliseconds(10)).status().code(), absl::StatusCode::kDeadlineExceeded);
  ASSERT_TRUE(cam.Trigger().ok());
  auto frame = cam.Retrieve(absl::Milliseconds(10));
  ASSERT_TRUE(frame.ok());
  EXPECT_EQ(frame->camera_name, "cam0");
  EXPECT_EQ(frame->frame_id, 1u);
  EXPECT_EQ(cam.Configure(CameraSettings{}).code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_TRUE(cam.StopAcquisition().ok());
}

TEST_F(SimulatedCameraTest, DisconnectedCameraFailsTheCapture) {
  static_cast<SimulatedCamera*>(cameras_[1].get())->Disconnect();
  auto bundle = CaptureStop(pointers_, rig_, CaptureRequest{});
  EXPECT_EQ(bundle.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_NE(bundle.status().message().find("cam1"), std::string::npos) << bundle.status();
}

TEST_F(SimulatedCameraTest, CaptureRejectsCameraWithoutCalibration) {
  RigCalibration partial = rig_;
  partial.cameras.pop_back();
  auto bundle = CaptureStop(pointers_, partial, CaptureRequest{});
  EXPECT_EQ(bundle.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bundle.status().message().find("cam2"), std::string::npos);
}

TEST_F(SimulatedCameraTest, InvalidSettingsAreRejected) {
  CaptureRequest request;
  request.settings.exposure_us = -5;
  auto bundle = CaptureStop(pointers_, rig_, request);
  EXPECT_EQ(bundle.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bundle.status().message().find("exposure_us"), std::string::npos) << bundle.status();
  CaptureRequest hardware;
  hardware.settings.trigger = TriggerMode::kHardware;
  EXPECT_EQ(CaptureStop(pointers_, rig_, hardware).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vb::capture
