// SPDX-License-Identifier: Apache-2.0
// End-to-end tests of the vinebot binary: its files, its exit codes and its error messages.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "core/cut_plan.h"
#include "core/json_io.h"
#include "core/trajectory.h"
#include "core/vine_model_json.h"
#include "gtest/gtest.h"
#include "sim/rig.h"
#include "sim/vine_generator.h"
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
  const std::string dir = ::testing::TempDir() + "/vinebot_cli_" + name + "_" +
                          std::to_string(getpid());
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
  // The simulated rig's flags are named as typed, not by the option field behind them; no stop
  // is rendered before the error.
  for (const char* bad : {"--rig-baseline 3", "--rig-apex-raise -0.1", "--rig-apex-aim-up 5",
                          "--rig-cameras 5", "--rig-upper-side 0"}) {
    run = Vinebot(std::string("bench reconstruct --vines 1 ") + bad);
    EXPECT_EQ(run.exit_code, 2) << bad;
    const std::string flag = std::string(bad).substr(0, std::string(bad).find(' '));
    EXPECT_NE(run.output.find(flag + ": "), std::string::npos) << run.output;
  }
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
                          "\"wire_recall\"", "\"head_enclosed_fraction\"",
                          "\"cut_error_median_m\"", "\"cuts_missed_fraction\"",
                          "\"cuts_on_kept_canes\""}) {
    EXPECT_NE(eval.output.find(key), std::string::npos) << key << " in " << eval.output;
  }
  // The model's left-out wood (its obstacles) is for the planner: the metrics are the same with
  // and without it, even with every true cane added as an obstacle.
  auto with_wood = ReadJsonFile(dir + "/model.json");
  ASSERT_TRUE(with_wood.ok()) << with_wood.status();
  auto truth = ReadVineModel(dir + "/ground_truth.json");
  ASSERT_TRUE(truth.ok()) << truth.status();
  nlohmann::json without_wood = *with_wood;
  without_wood.erase("obstacles");
  std::ofstream(dir + "/without_wood.json") << without_wood.dump();
  for (const Cane& cane : truth->canes) {
    VineModel one;
    one.obstacles.push_back(WoodObstacle{cane.polyline});
    (*with_wood)["obstacles"].push_back(VineModelToJson(one)["obstacles"][0]);
  }
  std::ofstream(dir + "/with_wood.json") << with_wood->dump();
  const RunResult eval_with =
      Vinebot("evaluate --model " + dir + "/with_wood.json --truth " + dir + "/ground_truth.json");
  const RunResult eval_without = Vinebot("evaluate --model " + dir + "/without_wood.json --truth " +
                                         dir + "/ground_truth.json");
  ASSERT_EQ(eval_with.exit_code, 0) << eval_with.output;
  EXPECT_EQ(eval_with.output, eval_without.output);
  EXPECT_EQ(eval_with.output, eval.output);
  // The job's plan stage on the reconstruction: its obstacles and the stop's calibration.
  ASSERT_EQ(Vinebot("decide --model " + dir + "/model.json --out " + dir + "/cuts.json").exit_code,
            0);
  const RunResult plan = Vinebot("plan --model " + dir + "/model.json --cuts " + dir +
                                 "/cuts.json --calibration " + dir + "/calibration.yaml --out " +
                                 dir + "/trajectory.json");
  ASSERT_EQ(plan.exit_code, 0) << plan.output;
  EXPECT_TRUE(ReadTrajectory(dir + "/trajectory.json").ok());
  const RunResult bench =
      Vinebot("bench reconstruct --vines 1 --seed-base 1014 --tolerances-mm 10,30");
  ASSERT_EQ(bench.exit_code, 0) << bench.output;
  EXPECT_NE(bench.output.find("\"stage_median_s\""), std::string::npos) << bench.output;
  EXPECT_NE(bench.output.find("\"cut_metrics\""), std::string::npos) << bench.output;
  // Scored at 10 mm the metrics are the bench's own; a looser match distance finds at least as
  // much of the truth near the model and of the model near the truth.
  const nlohmann::json summary = nlohmann::json::parse(bench.output);
  const nlohmann::json& at10 = summary["by_tolerance_mm"]["10"];
  const nlohmann::json& at30 = summary["by_tolerance_mm"]["30"];
  for (const char* key : {"cane_recall", "cane_precision", "connectivity"}) {
    EXPECT_EQ(at10[key].get<double>(), summary["mean"][key].get<double>()) << key;
    EXPECT_GE(at30[key].get<double>(), at10[key].get<double>()) << key;
  }
  EXPECT_GT(at30["cane_recall"].get<double>(), at10["cane_recall"].get<double>());
  const RunResult bad_tolerance = Vinebot("bench reconstruct --vines 1 --tolerances-mm 10,0");
  EXPECT_EQ(bad_tolerance.exit_code, 2);
  EXPECT_NE(bad_tolerance.output.find("--tolerances-mm: '0'"), std::string::npos)
      << bad_tolerance.output;
  std::filesystem::remove_all(dir);
}

TEST(VinebotCli, ReconstructRejectsBadInputNamingIt) {
  const std::string dir = FreshDir("reconstruct_bad");
  ASSERT_EQ(Vinebot("sim render --seed 1015 --vine 1 --cameras 1 --out " + dir).exit_code, 0);
  RunResult run = Vinebot("reconstruct --bundle " + dir + " --out " + dir + "/model.json");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("two cameras, the stop has 1 (cam0)"), std::string::npos)
      << run.output;
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

namespace vb {
namespace {

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A simulated vine's ground truth, written as a model file (no rendering needed).
std::string WriteSimTruth(const std::string& dir, uint64_t seed) {
  std::filesystem::create_directories(dir);
  auto scene = sim::GenerateScene(seed, 1);
  EXPECT_TRUE(scene.ok()) << scene.status();
  const std::string path = dir + "/truth.json";
  EXPECT_TRUE(WriteVineModel(path, scene->vine).ok());
  return path;
}

// The decide and phenomics commands end to end on a simulated ground truth: a valid cut plan
// (every cut on its cane, none on a kept cane), the same plan twice, the phenomics keys.
TEST(VinebotCli, DecideWritesAValidCutPlanForASimulatedVine) {
  const std::string dir = FreshDir("decide");
  const std::string truth_path = WriteSimTruth(dir, 4242);
  const RunResult run =
      Vinebot("decide --model " + truth_path + " --out " + dir + "/plan.json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("\"cuts\""), std::string::npos) << run.output;
  const auto truth = ReadVineModel(truth_path);
  ASSERT_TRUE(truth.ok()) << truth.status();
  const auto plan = ReadCutPlan(dir + "/plan.json");
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_TRUE(plan->ValidateAgainst(*truth).ok());
  EXPECT_FALSE(plan->keep.empty());
  EXPECT_FALSE(plan->cuts.empty());
  for (const Cut& cut : plan->cuts) {
    EXPECT_EQ(std::count(plan->keep.begin(), plan->keep.end(), cut.cane_id) > 0,
              cut.reason == CutReason::kShorten)
        << "cut " << cut.id.value;
    double distance = 1.0;
    truth->canes[*truth->IndexOf(cut.cane_id)].polyline.Project(cut.point, &distance);
    EXPECT_LE(distance, 0.001) << "cut " << cut.id.value;
  }
  ASSERT_EQ(Vinebot("decide --model " + truth_path + " --out " + dir + "/again.json").exit_code, 0);
  EXPECT_EQ(ReadText(dir + "/plan.json"), ReadText(dir + "/again.json"));

  for (const std::string& args : {std::string("--plan ") + dir + "/plan.json", std::string()}) {
    const RunResult pheno = Vinebot("phenomics --model " + truth_path + " " + args);
    ASSERT_EQ(pheno.exit_code, 0) << pheno.output;
    for (const char* key : {"\"canes_from_head\"", "\"canes_from_trunk\"", "\"canes_from_cane\"",
                            "\"cane_length_total_m\"", "\"cane_diameter_median_mm\"",
                            "\"cane_diameter_histogram\"", "\"trunk_diameter_mm\"",
                            "\"head_volume_m3\"", "\"pruning_weight_kg\"", "\"kept_length_m\"",
                            "\"cuts_by_reason\""}) {
      EXPECT_NE(pheno.output.find(key), std::string::npos) << key << " in " << pheno.output;
    }
    EXPECT_EQ(pheno.output.find("\"pruning_weight_kg\": null"), std::string::npos) << pheno.output;
  }
  const RunResult both = Vinebot("phenomics --model " + truth_path + " --plan " + dir +
                                 "/plan.json --policy " + dir + "/policy.json");
  EXPECT_EQ(both.exit_code, 2) << both.output;
  EXPECT_NE(both.output.find("--plan"), std::string::npos) << both.output;
  std::filesystem::remove_all(dir);
}

TEST(VinebotCli, DecideRejectsMalformedModelsNamingTheField) {
  const std::string dir = FreshDir("decide_bad");
  const std::string truth_path = WriteSimTruth(dir, 4243);
  const auto good = ReadJsonFile(truth_path);
  ASSERT_TRUE(good.ok()) << good.status();
  struct Case {
    const char* name;
    std::function<void(nlohmann::json&)> spoil;
    const char* expected;  // in the message
  };
  const std::vector<Case> cases = {
      {"cycle",
       [](nlohmann::json& j) {
         j["canes"][1]["parent_id"] = j["canes"][2]["id"];
         j["canes"][2]["parent_id"] = j["canes"][1]["id"];
       },
       "cycle"},
      {"unknown_parent", [](nlohmann::json& j) { j["canes"][2]["parent_id"] = 999999; },
       "parent_id 999999"},
      {"nan_point", [](nlohmann::json& j) { j["canes"][1]["points"][1][2] = "NaN"; },
       "canes[1].points[1]"},
      {"empty", [](nlohmann::json& j) { j["canes"] = nlohmann::json::array(); }, "empty"},
      {"radii", [](nlohmann::json& j) { j["canes"][3]["radii"].erase(0); }, "radii"},
  };
  for (const Case& c : cases) {
    nlohmann::json spoilt = *good;
    c.spoil(spoilt);
    const std::string path = dir + "/" + c.name + ".json";
    std::ofstream(path) << spoilt.dump();
    for (const std::string& command : {"decide --out " + dir + "/p.json", std::string("phenomics")}) {
      const RunResult run = Vinebot(command + " --model " + path);
      EXPECT_EQ(run.exit_code, 2) << command << " " << c.name << ": " << run.output;
      EXPECT_NE(run.output.find(c.expected), std::string::npos)
          << command << " " << c.name << ": " << run.output;
      EXPECT_NE(run.output.find(path), std::string::npos) << run.output;
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/p.json"));

  std::ofstream(dir + "/policy.json") << R"({"canes_to_keep": 9})";
  RunResult run = Vinebot("decide --model " + truth_path + " --policy " + dir +
                          "/policy.json --out " + dir + "/p.json");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("canes_to_keep"), std::string::npos) << run.output;
  std::ofstream(dir + "/policy.json") << R"({"cane_to_keep": 2})";
  run = Vinebot("decide --model " + truth_path + " --policy " + dir + "/policy.json --out " + dir +
                "/p.json");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("cane_to_keep"), std::string::npos) << run.output;
  run = Vinebot("decide --model " + truth_path + " --out " + dir + "/p.json --deadline-s 0");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("--deadline-s"), std::string::npos) << run.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/p.json"));
  std::filesystem::remove_all(dir);
}

// evaluate reports the cut-point metrics: exact on the truth itself, every cut missed (not an
// error) for an empty reconstruction.
TEST(VinebotCli, EvaluatePrintsTheCutPointMetrics) {
  const std::string dir = FreshDir("evaluate_cuts");
  const std::string truth_path = WriteSimTruth(dir, 4244);
  RunResult run = Vinebot("evaluate --model " + truth_path + " --truth " + truth_path);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  auto json = nlohmann::json::parse(run.output, nullptr, false);
  ASSERT_FALSE(json.is_discarded()) << run.output;
  for (const char* key : {"cut_error_median_m", "cut_error_p95_m", "cuts_missed_fraction",
                          "cuts_spurious_fraction", "cuts_on_kept_canes", "cane_recall"}) {
    EXPECT_TRUE(json.contains(key)) << key << " in " << run.output;
  }
  EXPECT_EQ(json["cuts_missed_fraction"], 0.0);
  EXPECT_EQ(json["cuts_spurious_fraction"], 0.0);
  EXPECT_EQ(json["cut_error_p95_m"], 0.0);
  EXPECT_EQ(json["cuts_on_kept_canes"], 0);

  auto empty = ReadJsonFile(truth_path);
  ASSERT_TRUE(empty.ok());
  (*empty)["canes"] = nlohmann::json::array();
  std::ofstream(dir + "/empty.json") << empty->dump();
  run = Vinebot("evaluate --model " + dir + "/empty.json --truth " + truth_path);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  json = nlohmann::json::parse(run.output, nullptr, false);
  ASSERT_FALSE(json.is_discarded()) << run.output;
  EXPECT_EQ(json["cuts_missed_fraction"], 1.0);
  EXPECT_TRUE(json.contains("model_decide_error")) << run.output;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace vb

namespace vb {
namespace {

// vinebot plan end to end on a simulated ground truth and its decided cut plan: a valid
// trajectory file whose cut segments and unplanned cuts account for every cut; bad input exits 2
// naming the file or flag.
TEST(VinebotCli, PlanWritesATrajectoryAccountingForEveryCut) {
  const std::string dir = FreshDir("plan");
  const std::string truth_path = WriteSimTruth(dir, 4242);
  ASSERT_EQ(Vinebot("decide --model " + truth_path + " --out " + dir + "/cuts.json").exit_code, 0);
  const RunResult run = Vinebot("plan --model " + truth_path + " --cuts " + dir +
                                "/cuts.json --out " + dir + "/trajectory.json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("\"planned\""), std::string::npos) << run.output;
  const auto trajectory = ReadTrajectory(dir + "/trajectory.json");
  ASSERT_TRUE(trajectory.ok()) << trajectory.status();
  const auto plan = ReadCutPlan(dir + "/cuts.json");
  ASSERT_TRUE(plan.ok()) << plan.status();
  size_t cut_segments = 0;
  for (const TrajectorySegment& s : trajectory->segments) cut_segments += s.kind == SegmentKind::kCut;
  EXPECT_EQ(cut_segments + trajectory->unplanned.size(), plan->cuts.size());
  EXPECT_GT(cut_segments, 0u);
  EXPECT_EQ(trajectory->tool.name, "secateur");

  // A cut plan naming a cane the model lacks, a missing file, an unknown tool.
  std::ofstream(dir + "/bad.json")
      << R"({"format":"vinebot.cut_plan.v1","policy":{},"keep":[],"spurs":[],"cuts":[)"
      << R"({"id":1,"cane_id":999,"point":[0,0.8,1],"direction":[1,0,0],"diameter_m":0.01,)"
      << R"("reason":"remove"}]})";
  RunResult bad = Vinebot("plan --model " + truth_path + " --cuts " + dir + "/bad.json --out " +
                          dir + "/t.json");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("bad.json"), std::string::npos) << bad.output;
  bad = Vinebot("plan --model " + dir + "/none.json --cuts " + dir + "/cuts.json --out " + dir +
                "/t.json");
  EXPECT_NE(bad.exit_code, 0) << bad.output;
  EXPECT_NE(bad.output.find("none.json"), std::string::npos) << bad.output;
  bad = Vinebot("plan --model " + truth_path + " --cuts " + dir + "/cuts.json --out " + dir +
                "/t.json --tool chainsaw");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--tool"), std::string::npos) << bad.output;
  bad = Vinebot("plan --model " + truth_path + " --cuts " + dir + "/cuts.json --out " + dir +
                "/t.json --calibration " + dir + "/no_calibration.yaml");
  EXPECT_NE(bad.exit_code, 0) << bad.output;
  EXPECT_NE(bad.output.find("--calibration"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("no_calibration.yaml"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/t.json"));
  // With the rig's calibration (the simulator's default rig): planned as well.
  auto rig = sim::MakeRig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  ASSERT_TRUE(capture::WriteCalibrationYaml(dir + "/calibration.yaml", *rig).ok());
  const RunResult calibrated = Vinebot("plan --model " + truth_path + " --cuts " + dir +
                                       "/cuts.json --calibration " + dir +
                                       "/calibration.yaml --out " + dir + "/calibrated.json");
  ASSERT_EQ(calibrated.exit_code, 0) << calibrated.output;
  const auto calibrated_trajectory = ReadTrajectory(dir + "/calibrated.json");
  ASSERT_TRUE(calibrated_trajectory.ok()) << calibrated_trajectory.status();
  size_t calibrated_cuts = 0;
  for (const TrajectorySegment& s : calibrated_trajectory->segments)
    calibrated_cuts += s.kind == SegmentKind::kCut;
  EXPECT_EQ(calibrated_cuts + calibrated_trajectory->unplanned.size(), plan->cuts.size());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace vb
