// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/scheme_learning.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/expert_pruner.h"
#include "sim/vine_generator.h"

namespace vb::decide {
namespace {

using ::testing::HasSubstr;

// Simulated vines [seed_begin, seed_begin + count) labelled by the expert rule set, as
// `vinebot sim decide-labels` writes them; examples the search cannot represent are skipped.
std::vector<RankingExample> ExpertExamples(uint64_t seed_begin, int count, int* skipped = nullptr) {
  std::vector<RankingExample> out;
  const PruningPolicy policy;
  for (int i = 0; i < count; ++i) {
    const uint64_t seed = seed_begin + i;
    absl::StatusOr<sim::Scene> scene = sim::GenerateScene(seed, static_cast<int>(seed % 7));
    EXPECT_TRUE(scene.ok()) << scene.status();
    absl::StatusOr<sim::ExpertDecision> d = sim::ExpertPrune(scene->vine, policy);
    EXPECT_TRUE(d.ok()) << d.status();
    LabelledExample e;
    e.name = "sim-" + std::to_string(seed);
    e.model = scene->vine;
    e.plan.policy = policy;
    e.plan.keep = d->keep;
    e.plan.spurs = d->spurs;
    absl::StatusOr<RankingExample> r = MakeRankingExample(e);
    if (r.ok()) {
      out.push_back(*std::move(r));
    } else {
      EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition) << r.status();
      if (skipped != nullptr) ++*skipped;
    }
  }
  return out;
}

// Relabels `examples` with the cheapest scheme under `weights` (a teacher the model can express).
std::vector<RankingExample> Relabelled(std::vector<RankingExample> examples,
                                       const SchemeWeights& weights) {
  for (RankingExample& e : examples) {
    absl::StatusOr<Scheme> best = FindBestScheme(e.candidates, e.policy, weights);
    EXPECT_TRUE(best.ok()) << best.status();
    e.expert = *best;
  }
  return examples;
}

SchemeWeights RandomWeights(uint64_t seed) {
  SchemeWeights w;
  uint64_t state = seed;
  for (int f = 0; f < kSchemeFeatureCount; ++f) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    w.w[f] = static_cast<double>(state >> 11) / 9007199254740992.0 * 2.0 - 1.0;  // [-1, 1)
  }
  return w;
}

// The acceptance test of issue 4 in small: learned on simulated vines labelled by the expert
// rule set, the weights reproduce the expert on vines from a disjoint seed range; random weights
// and zero weights do not.
TEST(SchemeLearning, LearnedWeightsReproduceTheExpertOnHeldOutVines) {
  int skipped = 0;
  const std::vector<RankingExample> train = ExpertExamples(1100, 80, &skipped);
  const std::vector<RankingExample> held_out = ExpertExamples(5000, 40, &skipped);
  ASSERT_GE(train.size(), 70u);
  ASSERT_GE(held_out.size(), 35u);

  absl::StatusOr<SchemeLearningResult> learned = LearnSchemeWeights(train);
  ASSERT_TRUE(learned.ok()) << learned.status();
  EXPECT_GE(learned->train_agreement, 0.9);
  absl::StatusOr<AgreementReport> report = MeasureAgreement(held_out, learned->weights);
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_GE(report->agreement, 0.9) << "held-out disagreements: " << report->disagreements.size();

  for (uint64_t seed : {1u, 2u, 3u}) {
    absl::StatusOr<AgreementReport> random = MeasureAgreement(held_out, RandomWeights(seed));
    ASSERT_TRUE(random.ok()) << random.status();
    EXPECT_LT(random->agreement, 0.3) << "random weights, seed " << seed;
  }
  absl::StatusOr<AgreementReport> zero = MeasureAgreement(held_out, SchemeWeights{});
  ASSERT_TRUE(zero.ok());
  EXPECT_LT(zero->agreement, 0.3);
}

// With labels from a linear teacher the model can express exactly, the learner recovers the
// teacher's choices (a check on the optimiser, independent of the expert rule set).
TEST(SchemeLearning, RecoversALinearTeacher) {
  const SchemeWeights teacher = DefaultSchemeWeights();
  const std::vector<RankingExample> train = Relabelled(ExpertExamples(1200, 50), teacher);
  const std::vector<RankingExample> held_out = Relabelled(ExpertExamples(5100, 30), teacher);
  absl::StatusOr<SchemeLearningResult> learned = LearnSchemeWeights(train);
  ASSERT_TRUE(learned.ok()) << learned.status();
  absl::StatusOr<AgreementReport> report = MeasureAgreement(held_out, learned->weights);
  ASSERT_TRUE(report.ok());
  EXPECT_GE(report->agreement, 0.9);
}

TEST(SchemeLearning, IsDeterministic) {
  const std::vector<RankingExample> train = ExpertExamples(1300, 20);
  absl::StatusOr<SchemeLearningResult> a = LearnSchemeWeights(train);
  absl::StatusOr<SchemeLearningResult> b = LearnSchemeWeights(train);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->weights.w, b->weights.w);
  EXPECT_EQ(a->rounds, b->rounds);
}

TEST(SchemeLearning, OneSwapNeighboursAreFeasibleDistinctAlternatives) {
  const std::vector<RankingExample> examples = ExpertExamples(1100, 5);
  ASSERT_FALSE(examples.empty());
  for (const RankingExample& e : examples) {
    const std::vector<Scheme> n = OneSwapNeighbours(e);
    EXPECT_GT(n.size(), 5u) << e.name;
    EXPECT_EQ(std::set<Scheme>(n.begin(), n.end()).size(), n.size());
    for (const Scheme& s : n) {
      EXPECT_NE(s, e.expert);
      EXPECT_TRUE(IsFeasible(e.candidates, e.policy, s));
      const double loss = SchemeLoss(e.expert, s, 4.0);  // one swap: 2, 8 or 10
      EXPECT_TRUE(loss == 2.0 || loss == 8.0 || loss == 10.0) << loss;
    }
  }
}

TEST(SchemeLearning, SchemeLossWeighsKeptCanesAboveSpurs) {
  const Scheme a{{CaneId(2), CaneId(3)}, {CaneId(4)}};
  EXPECT_EQ(SchemeLoss(a, a, 4.0), 0.0);
  EXPECT_EQ(SchemeLoss(a, {{CaneId(2), CaneId(5)}, {CaneId(4)}}, 4.0), 8.0);   // 3 out, 5 in
  EXPECT_EQ(SchemeLoss(a, {{CaneId(2), CaneId(4)}, {CaneId(3)}}, 4.0), 10.0);  // roles traded
  EXPECT_EQ(SchemeLoss(a, {{CaneId(2), CaneId(3)}, {CaneId(6)}}, 4.0), 2.0);   // another spur
  EXPECT_EQ(SchemeLoss(a, {{CaneId(2), CaneId(3)}, {}}, 1.0), 1.0);
}

TEST(SchemeLearning, MakeRankingExampleRejectsSchemesTheSearchCannotPick) {
  absl::StatusOr<sim::Scene> scene = sim::GenerateScene(1100, 1);
  ASSERT_TRUE(scene.ok());
  LabelledExample e;
  e.name = "bad";
  e.model = scene->vine;
  e.plan.keep = {CaneId(1)};  // the trunk is never a candidate
  absl::StatusOr<RankingExample> trunk = MakeRankingExample(e);
  ASSERT_EQ(trunk.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(trunk.status().message(), HasSubstr("bad"));

  absl::StatusOr<sim::ExpertDecision> d = sim::ExpertPrune(scene->vine, e.plan.policy);
  ASSERT_TRUE(d.ok());
  e.plan.keep = d->keep;
  e.plan.spurs = {};  // the policy asks for two spurs
  EXPECT_EQ(MakeRankingExample(e).status().code(), absl::StatusCode::kFailedPrecondition);
  e.plan.spurs = d->spurs;
  EXPECT_TRUE(MakeRankingExample(e).ok());
}

TEST(SchemeLearning, RejectsBadOptionsAndNoExamples) {
  SchemeLearningOptions options;
  options.regularization = 0.0;
  EXPECT_THAT(options.Validate().message(), HasSubstr("regularization"));
  options = {};
  options.max_rounds = 0;
  EXPECT_THAT(options.Validate().message(), HasSubstr("max_rounds"));
  EXPECT_EQ(LearnSchemeWeights({}).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(SchemeLearning, HoldOutIndicesAreAFixedSortedSubset) {
  const std::vector<size_t> a = HoldOutIndices(100, 0.3);
  EXPECT_EQ(a.size(), 30u);
  EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
  EXPECT_EQ(std::set<size_t>(a.begin(), a.end()).size(), a.size());
  EXPECT_LT(a.back(), 100u);
  EXPECT_EQ(a, HoldOutIndices(100, 0.3));
  EXPECT_NE(a.front() + 29, a.back());  // not simply the first or last 30
  EXPECT_TRUE(HoldOutIndices(10, 0.0).empty());
}

}  // namespace
}  // namespace vb::decide
