// SPDX-License-Identifier: Apache-2.0
// End-to-end tests of the vinebot binary: its files, its exit codes and its error messages.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/vine_model_json.h"
#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/capture/bundle.h"
#include "workers/capture/fake_camera_process.h"

namespace vb {
namespace {

struct RunResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

RunResult Vinebot(const std::string& args) {
  const std::string command = std::string(VB_BINARY_DIR) + "/app/vinebot " + args + " 2>&1";
  RunResult run;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return run;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) run.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

std::string FreshDir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/vinebot_cli_" + name;
  std::filesystem::remove_all(dir);
  return dir;
}

TEST(VinebotCli, SimRenderWritesTheDocumentedFiles) {
  const std::string dir = FreshDir("render");
  const RunResult run = Vinebot("sim render --seed 7 --vine 3 --out " + dir);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (const char* f : {"cam0.png", "cam1.png", "cam2.png", "calibration.yaml", "capture.json",
                        "ground_truth.json", "labels_cam0.png", "labels_cam1.png",
                        "labels_cam2.png"}) {
    EXPECT_TRUE(std::filesystem::exists(dir + "/" + f)) << f;
  }
  auto bundle = capture::ReadBundle(dir);
  ASSERT_TRUE(bundle.ok()) << bundle.status();
  EXPECT_EQ(bundle->images.size(), 3u);
  auto truth = ReadVineModel(dir + "/ground_truth.json");
  ASSERT_TRUE(truth.ok()) << truth.status();
  EXPECT_GE(truth->canes.size(), 9u);
  // Same seed and vine: the same vine.
  const std::string again = FreshDir("render_again");
  ASSERT_EQ(Vinebot("sim render --seed 7 --vine 3 --out " + again).exit_code, 0);
  auto truth_again = ReadVineModel(again + "/ground_truth.json");
  ASSERT_TRUE(truth_again.ok());
  EXPECT_EQ(VineModelToJson(*truth), VineModelToJson(*truth_again));
  std::filesystem::remove_all(dir);
  std::filesystem::remove_all(again);
}

TEST(VinebotCli, CaptureFromSimulatorWritesAnImportableBundle) {
  const std::string dir = FreshDir("capture");
  const RunResult run = Vinebot("capture --source sim --seed 3 --vine 1 --pixel-format bayer_gr8 --out " + dir);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  auto bundle = capture::ReadBundle(dir);
  ASSERT_TRUE(bundle.ok()) << bundle.status();
  EXPECT_EQ(bundle->images[0].format, PixelFormat::kBayerGr8);
  const RunResult info = Vinebot("bundle info --bundle " + dir);
  EXPECT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("\"valid\": true"), std::string::npos) << info.output;
  std::filesystem::remove_all(dir);
}

TEST(VinebotCli, CaptureFromAravisFakeCameraWritesAnImportableBundle) {
  auto fake = capture::fake_gv::FakeCameraProcess::Start({});  // 127.0.0.1, 512x512 frames
  ASSERT_TRUE(fake.ok()) << fake.status();
  sim::RigOptions rig_options;
  rig_options.camera_count = 1;
  rig_options.image_width = 512;
  rig_options.image_height = 512;
  auto rig = sim::MakeRig(rig_options);
  ASSERT_TRUE(rig.ok()) << rig.status();
  const std::string dir = FreshDir("aravis");
  std::filesystem::create_directories(dir);
  const std::string calibration = dir + "/rig.yaml";
  ASSERT_TRUE(capture::WriteCalibrationYaml(calibration, *rig).ok());
  const std::string out = dir + "/bundle";
  const RunResult run = Vinebot("capture --source aravis --devices cam0=127.0.0.1 --calibration " +
                                calibration + " --pixel-format bayer_rg8 --exposure-us 2000 --out " + out);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  auto bundle = capture::ReadBundle(out);
  ASSERT_TRUE(bundle.ok()) << bundle.status();
  ASSERT_EQ(bundle->images.size(), 1u);
  EXPECT_EQ(bundle->images[0].format, PixelFormat::kBayerRg8);
  EXPECT_EQ(bundle->images[0].width, 512);
  // A device whose frames disagree with the calibration is refused, naming both sizes.
  rig_options.image_width = 640;
  auto wrong = sim::MakeRig(rig_options);
  ASSERT_TRUE(wrong.ok());
  ASSERT_TRUE(capture::WriteCalibrationYaml(calibration, *wrong).ok());
  const RunResult bad = Vinebot("capture --source aravis --devices cam0=127.0.0.1 --calibration " +
                                calibration + " --out " + dir + "/bad");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("512x512"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad/capture.json"));
  std::filesystem::remove_all(dir);
}

TEST(VinebotCli, RejectsBadFlagsNamingThem) {
  RunResult run = Vinebot("sim render --seed 7 --vine 3");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--out"), std::string::npos) << run.output;
  run = Vinebot("sim render --seed x --out /tmp/never");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--seed"), std::string::npos) << run.output;
  run = Vinebot("sim render --out /tmp/never --pixel-format yuv");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("pixel-format"), std::string::npos) << run.output;
  run = Vinebot("sim render --out /tmp/never --colour red");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--colour"), std::string::npos) << run.output;
  run = Vinebot("capture --source webcam --out /tmp/never");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--source"), std::string::npos) << run.output;
  run = Vinebot("capture --source aravis --out /tmp/never --devices cam0 --calibration /nonexistent.yaml");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.output.find("nonexistent.yaml"), std::string::npos) << run.output;
  run = Vinebot("frobnicate");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("unknown command"), std::string::npos) << run.output;
  EXPECT_FALSE(std::filesystem::exists("/tmp/never"));
}

TEST(VinebotCli, BundleInfoNamesTheBrokenFile) {
  const std::string dir = FreshDir("broken");
  ASSERT_EQ(Vinebot("sim render --seed 1 --vine 0 --cameras 2 --out " + dir).exit_code, 0);
  std::filesystem::resize_file(dir + "/cam1.png", 1000);  // truncated
  const RunResult run = Vinebot("bundle info --bundle " + dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("cam1.png"), std::string::npos) << run.output;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace vb

namespace vb {
namespace {

// The reconstruction commands end to end: a Bayer stop with 1 px of calibration error is
// reconstructed into a valid model, evaluated against its ground truth with the documented keys,
// and the benchmark command prints its summary.
TEST(VinebotCli, ReconstructAndEvaluateASimulatedStop) {
  const std::string dir = FreshDir("reconstruct");
  ASSERT_EQ(Vinebot("sim render --seed 1013 --vine 1 --pixel-format bayer_rg8 "
                    "--calibration-error-px 1 --out " + dir).exit_code, 0);
  const RunResult run = Vinebot("reconstruct --bundle " + dir + " --out " + dir + "/model.json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("\"timings\""), std::string::npos) << run.output;
  const auto model = ReadVineModel(dir + "/model.json");
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_GE(model->canes.size(), 3u);
  const RunResult eval =
      Vinebot("evaluate --model " + dir + "/model.json --truth " + dir + "/ground_truth.json");
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  for (const char* key : {"\"cane_recall\"", "\"cane_precision\"", "\"connectivity\"",
                          "\"wire_recall\"", "\"head_enclosed_fraction\""}) {
    EXPECT_NE(eval.output.find(key), std::string::npos) << key << " in " << eval.output;
  }
  const RunResult bench = Vinebot("bench reconstruct --vines 1 --seed-base 1014");
  ASSERT_EQ(bench.exit_code, 0) << bench.output;
  EXPECT_NE(bench.output.find("\"stage_median_s\""), std::string::npos) << bench.output;
  std::filesystem::remove_all(dir);
}

TEST(VinebotCli, ReconstructRejectsBadInputNamingIt) {
  const std::string dir = FreshDir("reconstruct_bad");
  ASSERT_EQ(Vinebot("sim render --seed 1015 --vine 1 --cameras 1 --out " + dir).exit_code, 0);
  RunResult run = Vinebot("reconstruct --bundle " + dir + " --out " + dir + "/model.json");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("two cameras"), std::string::npos) << run.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/model.json"));
  run = Vinebot("reconstruct --bundle " + dir + "/missing --out " + dir + "/model.json");
  EXPECT_NE(run.exit_code, 0);
  run = Vinebot("evaluate --model " + dir + "/ground_truth.json --truth " + dir + "/nope.json");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.output.find("nope.json"), std::string::npos) << run.output;
  run = Vinebot("reconstruct --bundle " + dir + " --out x.json --deadline-s -1");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("--deadline-s"), std::string::npos) << run.output;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace vb
