// SPDX-License-Identifier: Apache-2.0
// AravisCamera against Aravis' fake GigE Vision camera (real GVCP/GVSP over loopback), plus the
// device-independent CameraSettings::Validate and GrabSynchronised with an in-test fake Camera.
#include "workers/capture/aravis_camera.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "workers/capture/camera.h"
#include "workers/capture/fake_camera_process.h"

namespace vb::capture {
namespace {

using ::testing::HasSubstr;

// ---------------------------------------------------------------------------------------------
// CameraSettings::Validate

TEST(CameraSettings, DefaultsAreValid) { EXPECT_TRUE(CameraSettings{}.Validate().ok()); }

TEST(CameraSettings, RejectsBadExposure) {
  for (double exposure_us : {-1.0, 0.0, 1e12, std::nan(""), HUGE_VAL}) {
    CameraSettings settings;
    settings.exposure_us = exposure_us;
    const absl::Status status = settings.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << exposure_us;
    EXPECT_THAT(std::string(status.message()), HasSubstr("exposure_us")) << exposure_us;
  }
}

TEST(CameraSettings, RejectsBadGain) {
  for (double gain_db : {-0.5, 1000.0, std::nan("")}) {
    CameraSettings settings;
    settings.gain_db = gain_db;
    const absl::Status status = settings.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << gain_db;
    EXPECT_THAT(std::string(status.message()), HasSubstr("gain_db")) << gain_db;
  }
}

TEST(CameraSettings, RejectsUnknownEnumValues) {
  CameraSettings settings;
  settings.pixel_format = static_cast<PixelFormat>(42);
  EXPECT_THAT(std::string(settings.Validate().message()), HasSubstr("pixel_format"));
  settings = CameraSettings{};
  settings.trigger = static_cast<TriggerMode>(-3);
  EXPECT_THAT(std::string(settings.Validate().message()), HasSubstr("trigger"));
}

TEST(AravisCameraOptions, RejectsBadValues) {
  AravisCameraOptions options;
  EXPECT_TRUE(options.Validate().ok());
  options.n_buffers = 0;
  EXPECT_THAT(std::string(options.Validate().message()), HasSubstr("n_buffers"));
  options = AravisCameraOptions{};
  options.hardware_trigger_source = "";
  EXPECT_THAT(std::string(options.Validate().message()), HasSubstr("hardware_trigger_source"));
}

// ---------------------------------------------------------------------------------------------
// GrabSynchronised with a scripted in-test camera.

class ScriptedCamera : public Camera {
 public:
  ScriptedCamera(std::string name, std::vector<std::string>* log) : name_(name), log_(log) {}
  const std::string& name() const override { return name_; }
  absl::Status Open() override { return absl::OkStatus(); }
  absl::Status Configure(const CameraSettings&) override { return absl::OkStatus(); }
  absl::Status StartAcquisition() override { return absl::OkStatus(); }
  absl::Status Trigger() override {
    log_->push_back("trigger " + name_);
    if (!trigger_status.ok()) return trigger_status;
    ++pending_;
    return absl::OkStatus();
  }
  absl::StatusOr<Frame> Retrieve(absl::Duration timeout) override {
    log_->push_back("retrieve " + name_);
    last_timeout = timeout;
    if (never_delivers || pending_ == 0) {
      absl::SleepFor(timeout);
      return absl::DeadlineExceededError("no frame");
    }
    --pending_;
    Frame frame;
    frame.camera_name = name_;
    frame.image = Image(4, 3, PixelFormat::kMono8);
    frame.frame_id = ++frame_id_;
    return frame;
  }
  absl::Status StopAcquisition() override { return absl::OkStatus(); }
  void Close() override {}

  absl::Status trigger_status;
  bool never_delivers = false;
  absl::Duration last_timeout = absl::InfiniteDuration();

 private:
  std::string name_;
  std::vector<std::string>* log_;
  int pending_ = 0;
  uint64_t frame_id_ = 0;
};

TEST(GrabSynchronised, TriggersAllThenReturnsFramesInCameraOrder) {
  std::vector<std::string> log;
  ScriptedCamera a("cam0", &log), b("cam1", &log), c("cam2", &log);
  std::vector<Camera*> cameras = {&a, &b, &c};
  absl::StatusOr<std::vector<Frame>> frames = GrabSynchronised(cameras, absl::Seconds(1));
  ASSERT_TRUE(frames.ok()) << frames.status();
  ASSERT_EQ(frames->size(), 3u);
  EXPECT_EQ((*frames)[0].camera_name, "cam0");
  EXPECT_EQ((*frames)[1].camera_name, "cam1");
  EXPECT_EQ((*frames)[2].camera_name, "cam2");
  EXPECT_THAT(log, ::testing::ElementsAre("trigger cam0", "trigger cam1", "trigger cam2",
                                          "retrieve cam0", "retrieve cam1", "retrieve cam2"));
}

TEST(GrabSynchronised, TriggerFailureFailsPrefixedWithCameraName) {
  std::vector<std::string> log;
  ScriptedCamera a("cam0", &log), b("cam1", &log);
  b.trigger_status = absl::UnavailableError("device lost");
  std::vector<Camera*> cameras = {&a, &b};
  absl::StatusOr<std::vector<Frame>> frames = GrabSynchronised(cameras, absl::Seconds(1));
  EXPECT_EQ(frames.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(frames.status().message()), HasSubstr("cam1: device lost"));
}

TEST(GrabSynchronised, SilentCameraFailsWithDeadlineExceededWithinOneSharedTimeout) {
  std::vector<std::string> log;
  ScriptedCamera a("cam0", &log), b("cam1", &log);
  a.never_delivers = true;
  std::vector<Camera*> cameras = {&b, &a};
  const absl::Duration timeout = absl::Milliseconds(200);
  absl::StatusOr<std::vector<Frame>> frames = GrabSynchronised(cameras, timeout);
  EXPECT_EQ(frames.status().code(), absl::StatusCode::kDeadlineExceeded);
  EXPECT_THAT(std::string(frames.status().message()), HasSubstr("cam0"));
  // The second camera only gets what is left of the shared deadline.
  EXPECT_LE(a.last_timeout, timeout);
}

TEST(GrabSynchronised, RejectsEmptyOrNullCameras) {
  std::vector<Camera*> none;
  EXPECT_EQ(GrabSynchronised(none, absl::Seconds(1)).status().code(),
            absl::StatusCode::kInvalidArgument);
  std::vector<Camera*> with_null = {nullptr};
  EXPECT_EQ(GrabSynchronised(with_null, absl::Seconds(1)).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// ---------------------------------------------------------------------------------------------
// AravisCamera against arv-fake-gv-camera-0.8.

// The loopback addresses fake cameras can listen on in this process. Entering a private network
// namespace happens once, on the first call, from the main (test) thread before any Aravis use.
const std::vector<std::string>& FakeAddresses() {
  static const std::vector<std::string>* addresses = [] {
    auto* usable = new std::vector<std::string>;
    const absl::Status private_net = fake_gv::EnterPrivateLoopbackNetwork(3);
    if (!private_net.ok()) {
      std::fprintf(stderr, "[aravis test] no private network namespace (%s); using the host's lo\n",
                   std::string(private_net.message()).c_str());
    }
    for (const char* address : {"127.0.0.1", "127.0.0.2", "127.0.0.3"}) {
      if (fake_gv::IsInterfaceAddress(address)) usable->push_back(address);
    }
    return usable;
  }();
  return *addresses;
}

constexpr absl::Duration kFrameTimeout = absl::Seconds(3);

class AravisCameraTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_FALSE(FakeAddresses().empty()) << "no loopback address for the fake camera";
  }

  // Starts a fake camera on the index-th loopback address (skips the test if there is none).
  std::unique_ptr<fake_gv::FakeCameraProcess> StartFake(size_t index, std::string serial,
                                                         std::string genicam_path = "") {
    if (index >= FakeAddresses().size()) return nullptr;
    fake_gv::FakeCameraProcess::Options options;
    options.address = FakeAddresses()[index];
    options.serial = std::move(serial);
    options.genicam_path = std::move(genicam_path);
    absl::StatusOr<std::unique_ptr<fake_gv::FakeCameraProcess>> fake =
        fake_gv::FakeCameraProcess::Start(options);
    EXPECT_TRUE(fake.ok()) << fake.status();
    return fake.ok() ? *std::move(fake) : nullptr;
  }

  static CameraSettings Settings(PixelFormat format) {
    CameraSettings settings;
    settings.exposure_us = 2000;
    settings.pixel_format = format;
    settings.trigger = TriggerMode::kSoftware;
    return settings;
  }
};

TEST_F(AravisCameraTest, OpensByAddressAndGrabsSoftwareTriggeredFrames) {
  auto fake = StartFake(0, "GRAB");
  ASSERT_NE(fake, nullptr);
  AravisCamera camera("cam0", fake->address());
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Configure(Settings(PixelFormat::kMono8)).ok());
  ASSERT_TRUE(camera.StartAcquisition().ok());
  uint64_t last_id = 0;
  int64_t last_timestamp_ns = 0;
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(camera.Trigger().ok());
    absl::StatusOr<Frame> frame = camera.Retrieve(kFrameTimeout);
    ASSERT_TRUE(frame.ok()) << frame.status();
    EXPECT_EQ(frame->camera_name, "cam0");
    EXPECT_EQ(frame->image.width, 512);
    EXPECT_EQ(frame->image.height, 512);
    EXPECT_EQ(frame->image.format, PixelFormat::kMono8);
    EXPECT_EQ(frame->image.data.size(), 512u * 512u);
    if (i > 0) {
      EXPECT_GT(frame->frame_id, last_id);
      EXPECT_GT(frame->timestamp_ns, last_timestamp_ns);
    }
    EXPECT_GT(frame->timestamp_ns, 0);
    last_id = frame->frame_id;
    last_timestamp_ns = frame->timestamp_ns;
  }
  EXPECT_TRUE(camera.StopAcquisition().ok());
  camera.Close();
  camera.Close();  // idempotent
}

TEST_F(AravisCameraTest, OpensByDeviceIdAndReopensAfterClose) {
  auto fake = StartFake(0, "BYID");
  ASSERT_NE(fake, nullptr);
  AravisCamera camera("cam0", fake->device_id());
  ASSERT_TRUE(camera.Open().ok());
  camera.Close();
  ASSERT_TRUE(camera.Open().ok());
  EXPECT_TRUE(camera.Configure(Settings(PixelFormat::kMono8)).ok());
}

TEST_F(AravisCameraTest, DeliversEveryVinebotPixelFormat) {
  auto fake = StartFake(0, "FORMATS");
  ASSERT_NE(fake, nullptr);
  AravisCamera camera("cam0", fake->address());
  ASSERT_TRUE(camera.Open().ok());
  for (PixelFormat format : {PixelFormat::kRgb8, PixelFormat::kMono8, PixelFormat::kBayerRg8,
                             PixelFormat::kBayerGb8, PixelFormat::kBayerGr8,
                             PixelFormat::kBayerBg8}) {
    SCOPED_TRACE(std::string(PixelFormatName(format)));
    ASSERT_TRUE(camera.Configure(Settings(format)).ok());
    ASSERT_TRUE(camera.StartAcquisition().ok());
    ASSERT_TRUE(camera.Trigger().ok());
    absl::StatusOr<Frame> frame = camera.Retrieve(kFrameTimeout);
    ASSERT_TRUE(frame.ok()) << frame.status();
    EXPECT_EQ(frame->image.format, format);
    EXPECT_EQ(frame->image.data.size(), 512u * 512u * ChannelCount(format));
    ASSERT_TRUE(camera.StopAcquisition().ok());
  }
}

TEST_F(AravisCameraTest, GrabSynchronisedOverThreeFakeCameras) {
  if (FakeAddresses().size() < 3) {
    GTEST_SKIP() << "needs 127.0.0.1-3 on an interface (private network namespace unavailable)";
  }
  std::vector<std::unique_ptr<fake_gv::FakeCameraProcess>> fakes;
  std::vector<std::unique_ptr<AravisCamera>> cameras;
  std::vector<Camera*> rig;
  for (int i = 0; i < 3; ++i) {
    fakes.push_back(StartFake(i, "RIG" + std::to_string(i)));
    ASSERT_NE(fakes.back(), nullptr);
    cameras.push_back(
        std::make_unique<AravisCamera>("cam" + std::to_string(i), fakes.back()->address()));
    ASSERT_TRUE(cameras.back()->Open().ok());
    ASSERT_TRUE(cameras.back()->Configure(Settings(PixelFormat::kBayerRg8)).ok());
    ASSERT_TRUE(cameras.back()->StartAcquisition().ok());
    rig.push_back(cameras.back().get());
  }
  for (int set = 0; set < 2; ++set) {
    absl::StatusOr<std::vector<Frame>> frames = GrabSynchronised(rig, kFrameTimeout);
    ASSERT_TRUE(frames.ok()) << frames.status();
    ASSERT_EQ(frames->size(), 3u);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ((*frames)[i].camera_name, "cam" + std::to_string(i));
      EXPECT_EQ((*frames)[i].image.format, PixelFormat::kBayerRg8);
      EXPECT_EQ((*frames)[i].image.data.size(), 512u * 512u);
    }
  }
}

TEST_F(AravisCameraTest, RetrieveWithoutTriggerFailsWithDeadlineExceeded) {
  auto fake = StartFake(0, "NOTRIG");
  ASSERT_NE(fake, nullptr);
  AravisCamera camera("cam0", fake->address());
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Configure(Settings(PixelFormat::kMono8)).ok());
  ASSERT_TRUE(camera.StartAcquisition().ok());
  const absl::Duration timeout = absl::Milliseconds(300);
  const absl::Time start = absl::Now();
  absl::StatusOr<Frame> frame = camera.Retrieve(timeout);
  const absl::Duration elapsed = absl::Now() - start;
  EXPECT_EQ(frame.status().code(), absl::StatusCode::kDeadlineExceeded) << frame.status();
  EXPECT_GE(elapsed, timeout - absl::Milliseconds(20));
  EXPECT_LT(elapsed, timeout + absl::Seconds(2));  // a bound, not a benchmark
  // The stream still works afterwards.
  ASSERT_TRUE(camera.Trigger().ok());
  EXPECT_TRUE(camera.Retrieve(kFrameTimeout).ok());
}

TEST_F(AravisCameraTest, OpenWithoutCameraFailsCleanly) {
  // Nothing listens on the last usable address (no fake started in this test).
  const std::string address = FakeAddresses().back();
  ASSERT_FALSE(fake_gv::GvcpAnswers(address, absl::Milliseconds(100)));
  AravisCamera camera("cam2", address);
  const absl::Time start = absl::Now();
  const absl::Status status = camera.Open();
  EXPECT_TRUE(absl::IsNotFound(status) || absl::IsUnavailable(status)) << status;
  EXPECT_THAT(std::string(status.message()), HasSubstr(address));
  EXPECT_THAT(std::string(status.message()), HasSubstr("cam2"));
  EXPECT_LT(absl::Now() - start, absl::Seconds(10));
  EXPECT_EQ(camera.Configure(CameraSettings{}).code(), absl::StatusCode::kFailedPrecondition);
  camera.Close();
}

TEST_F(AravisCameraTest, UnsupportedPixelFormatIsInvalidArgument) {
  const std::string genicam =
      absl::StrCat(::testing::TempDir(), "/vb_fake_no_rgb8_", getpid(), ".xml");
  ASSERT_TRUE(fake_gv::WriteFakeGenicamWithout({"RGB8"}, genicam).ok());
  auto fake = StartFake(0, "MONOONLY", genicam);
  ASSERT_NE(fake, nullptr);
  AravisCamera camera("cam0", fake->address());
  ASSERT_TRUE(camera.Open().ok());
  const absl::Status status = camera.Configure(Settings(PixelFormat::kRgb8));
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << status;
  EXPECT_THAT(std::string(status.message()), HasSubstr("pixel_format"));
  EXPECT_THAT(std::string(status.message()), HasSubstr("rgb8"));
  EXPECT_TRUE(camera.Configure(Settings(PixelFormat::kBayerGb8)).ok());
  std::remove(genicam.c_str());
}

TEST_F(AravisCameraTest, OutOfRangeExposureGainAndTriggerAreInvalidArgument) {
  auto fake = StartFake(0, "RANGES");
  ASSERT_NE(fake, nullptr);
  AravisCamera camera("cam0", fake->address());
  ASSERT_TRUE(camera.Open().ok());
  struct Case {
    std::function<void(CameraSettings&)> edit;
    std::string field;
  };
  const std::vector<Case> cases = {
      {[](CameraSettings& s) { s.exposure_us = -5; }, "exposure_us"},
      {[](CameraSettings& s) { s.exposure_us = 1e15; }, "exposure_us"},
      {[](CameraSettings& s) { s.exposure_us = 1; }, "exposure_us"},  // below the fake's 10 us
      {[](CameraSettings& s) { s.gain_db = -1; }, "gain_db"},
      {[](CameraSettings& s) { s.gain_db = 30; }, "gain_db"},  // above the fake's GainRaw 10
      {[](CameraSettings& s) { s.trigger = TriggerMode::kHardware; }, "trigger"},  // no Line1
  };
  for (const Case& c : cases) {
    CameraSettings settings = Settings(PixelFormat::kMono8);
    c.edit(settings);
    const absl::Status status = camera.Configure(settings);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << status;
    EXPECT_THAT(std::string(status.message()), HasSubstr(c.field)) << status;
  }
  // In range: accepted.
  CameraSettings settings = Settings(PixelFormat::kMono8);
  settings.exposure_us = 10;
  settings.gain_db = 10;
  EXPECT_TRUE(camera.Configure(settings).ok());
}

TEST_F(AravisCameraTest, HardwareTriggerOnAnOfferedLineWaitsForTheLine) {
  auto fake = StartFake(0, "HWTRIG");
  ASSERT_NE(fake, nullptr);
  AravisCameraOptions options;
  options.hardware_trigger_source = "Line0";  // the fake's only line
  AravisCamera camera("cam0", fake->address(), options);
  ASSERT_TRUE(camera.Open().ok());
  CameraSettings settings = Settings(PixelFormat::kMono8);
  settings.trigger = TriggerMode::kHardware;
  ASSERT_TRUE(camera.Configure(settings).ok());
  ASSERT_TRUE(camera.StartAcquisition().ok());
  EXPECT_TRUE(camera.Trigger().ok());  // a no-op in hardware mode
  EXPECT_EQ(camera.Retrieve(absl::Milliseconds(300)).status().code(),
            absl::StatusCode::kDeadlineExceeded);
}

TEST_F(AravisCameraTest, FreeRunningDeliversWithoutTrigger) {
  auto fake = StartFake(0, "FREE");
  ASSERT_NE(fake, nullptr);
  AravisCamera camera("cam0", fake->address());
  ASSERT_TRUE(camera.Open().ok());
  CameraSettings settings = Settings(PixelFormat::kMono8);
  settings.trigger = TriggerMode::kFreeRunning;
  ASSERT_TRUE(camera.Configure(settings).ok());
  ASSERT_TRUE(camera.StartAcquisition().ok());
  absl::StatusOr<Frame> first = camera.Retrieve(kFrameTimeout);
  ASSERT_TRUE(first.ok()) << first.status();
  absl::StatusOr<Frame> second = camera.Retrieve(kFrameTimeout);
  ASSERT_TRUE(second.ok()) << second.status();
  EXPECT_GT(second->frame_id, first->frame_id);
}

TEST_F(AravisCameraTest, LifecycleViolationsAreFailedPrecondition) {
  auto fake = StartFake(0, "LIFE");
  ASSERT_NE(fake, nullptr);
  AravisCamera camera("cam0", fake->address());
  EXPECT_EQ(camera.Configure(Settings(PixelFormat::kMono8)).code(),
            absl::StatusCode::kFailedPrecondition);
  ASSERT_TRUE(camera.Open().ok());
  EXPECT_EQ(camera.StartAcquisition().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(camera.Trigger().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(camera.Retrieve(absl::Milliseconds(10)).status().code(),
            absl::StatusCode::kFailedPrecondition);
  ASSERT_TRUE(camera.Configure(Settings(PixelFormat::kMono8)).ok());
  ASSERT_TRUE(camera.StartAcquisition().ok());
  EXPECT_EQ(camera.StartAcquisition().code(), absl::StatusCode::kFailedPrecondition);
  const absl::Status status = camera.Configure(Settings(PixelFormat::kRgb8));
  EXPECT_EQ(status.code(), absl::StatusCode::kFailedPrecondition) << status;
  // Still streaming after the refused Configure.
  ASSERT_TRUE(camera.Trigger().ok());
  absl::StatusOr<Frame> frame = camera.Retrieve(kFrameTimeout);
  ASSERT_TRUE(frame.ok()) << frame.status();
  EXPECT_EQ(frame->image.format, PixelFormat::kMono8);
  ASSERT_TRUE(camera.StopAcquisition().ok());
  EXPECT_TRUE(camera.Configure(Settings(PixelFormat::kRgb8)).ok());
}

TEST_F(AravisCameraTest, LossyStreamGivesDataLossNotCorruptFrames) {
  fake_gv::FakeCameraProcess::Options options;
  options.address = FakeAddresses()[0];
  options.serial = "LOSSY";
  options.gvsp_lost_per_thousand = 500;  // half the stream packets never arrive
  absl::StatusOr<std::unique_ptr<fake_gv::FakeCameraProcess>> fake =
      fake_gv::FakeCameraProcess::Start(options);
  ASSERT_TRUE(fake.ok()) << fake.status();
  AravisCamera camera("cam0", (*fake)->address());
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Configure(Settings(PixelFormat::kMono8)).ok());
  ASSERT_TRUE(camera.StartAcquisition().ok());
  int data_loss = 0;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(camera.Trigger().ok());
    absl::StatusOr<Frame> frame = camera.Retrieve(absl::Seconds(1));
    // A complete frame is (almost) impossible at 50 % loss; a frame must never come back corrupt.
    EXPECT_FALSE(frame.ok()) << "frame " << frame->frame_id;
    if (absl::IsDataLoss(frame.status())) {
      ++data_loss;
      EXPECT_THAT(std::string(frame.status().message()), HasSubstr("buffer status"));
    } else {
      EXPECT_TRUE(absl::IsDeadlineExceeded(frame.status())) << frame.status();
    }
  }
  EXPECT_GT(data_loss, 0);
}

TEST_F(AravisCameraTest, KilledCameraGivesErrorsNotCrashOrHang) {
  auto fake = StartFake(0, "KILLED");
  ASSERT_NE(fake, nullptr);
  AravisCamera camera("cam0", fake->address());
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Configure(Settings(PixelFormat::kMono8)).ok());
  ASSERT_TRUE(camera.StartAcquisition().ok());
  ASSERT_TRUE(camera.Trigger().ok());
  ASSERT_TRUE(camera.Retrieve(kFrameTimeout).ok());

  fake->Kill();
  const absl::Time start = absl::Now();
  absl::StatusOr<Frame> frame = camera.Retrieve(absl::Milliseconds(500));
  EXPECT_TRUE(absl::IsDeadlineExceeded(frame.status()) || absl::IsUnavailable(frame.status()))
      << frame.status();
  const absl::Status trigger = camera.Trigger();
  EXPECT_TRUE(absl::IsUnavailable(trigger)) << trigger;
  EXPECT_THAT(std::string(trigger.message()), HasSubstr("cam0"));
  // Once lost, everything fails fast.
  EXPECT_TRUE(absl::IsUnavailable(camera.Retrieve(absl::Seconds(5)).status()));
  EXPECT_TRUE(absl::IsUnavailable(camera.Trigger()));
  camera.Close();
  EXPECT_LT(absl::Now() - start, absl::Seconds(15));  // bounded, not hung
}

}  // namespace
}  // namespace vb::capture
