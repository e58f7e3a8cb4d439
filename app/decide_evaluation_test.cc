// SPDX-License-Identifier: Apache-2.0
#include "app/decide_evaluation.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "gtest/gtest.h"
#include "sim/vine_generator.h"

namespace vb::app {
namespace {

TEST(EvaluateDecidedCuts, TruthAgainstItselfIsExact) {
  auto scene = sim::GenerateScene(4300, 1);
  ASSERT_TRUE(scene.ok()) << scene.status();
  auto m = EvaluateDecidedCuts(scene->vine, scene->vine, PruningPolicy{});
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_GT(m->metrics.truth_cuts, 0);
  EXPECT_EQ(m->metrics.matched_cuts, m->metrics.truth_cuts);
  EXPECT_EQ(m->metrics.cuts_missed_fraction, 0.0);
  EXPECT_EQ(m->metrics.cuts_on_kept_canes, 0);
  EXPECT_TRUE(m->model_decide_error.empty());
  EXPECT_FALSE(DecidedCutMetricsToJson(*m).contains("model_decide_error"));
}

TEST(EvaluateDecidedCuts, AnEmptyReconstructionMissesEveryCut) {
  auto scene = sim::GenerateScene(4301, 1);
  ASSERT_TRUE(scene.ok()) << scene.status();
  auto m = EvaluateDecidedCuts(VineModel{}, scene->vine, PruningPolicy{});
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->metrics.cuts_missed_fraction, 1.0);
  EXPECT_EQ(m->metrics.model_cuts, 0);
  EXPECT_NE(m->model_decide_error.find("empty"), std::string::npos) << m->model_decide_error;
  EXPECT_TRUE(DecidedCutMetricsToJson(*m).contains("model_decide_error"));
}

TEST(EvaluateDecidedCuts, AnEmptyTruthFails) {
  auto m = EvaluateDecidedCuts(VineModel{}, VineModel{}, PruningPolicy{});
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("truth: "), std::string_view::npos) << m.status();
}

TEST(PolicyAndWeightFiles, DefaultsWhenNoPathAndErrorsNameTheFile) {
  auto policy = PolicyOrDefault("");
  ASSERT_TRUE(policy.ok());
  EXPECT_EQ(policy->canes_to_keep, PruningPolicy{}.canes_to_keep);
  auto weights = WeightsOrDefault("");
  ASSERT_TRUE(weights.ok());
  EXPECT_EQ(weights->w, decide::DefaultSchemeWeights().w);
  const std::string path = ::testing::TempDir() + "/vinebot_bad_weights_" +
                           std::to_string(getpid()) + ".json";
  std::ofstream(path) << R"({"version": 1, "weights": {"no_such_feature": 1}})";
  weights = WeightsOrDefault(path);
  ASSERT_FALSE(weights.ok());
  EXPECT_EQ(weights.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(weights.status().message().find(path), std::string_view::npos) << weights.status();
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace vb::app
