// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/match_classifier.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/reconstruct/correspondence.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/reconstruct.h"
#include "workers/reconstruct/synthetic_views.h"

namespace vb::reconstruct {
namespace {

struct TrainingStop {
  std::vector<LabelledMatch> multi_view;
  std::vector<LabelledMatch> two_view;
};

// Every fitted candidate of `sim_stop`, labelled against ground truth: right iff >= 90% of its
// points lie within 1 cm of one true cane. With `refined`, the candidates of the pipeline's
// second pass: the rig and views as MatchWithRigRefinement leaves them (what the final model is
// built from); otherwise those of the first pass, with the rig as calibrated.
TrainingStop MakeTrainingStop(const SimulatedStop& sim_stop, bool refined = false) {
  std::vector<const Polyline3*> truth;
  for (const Cane& cane : sim_stop.drawn.canes) truth.push_back(&cane.polyline);
  RigCalibration rig = sim_stop.rig;
  std::vector<View2D> views = sim_stop.views;
  if (refined) {
    const auto matched =
        MatchWithRigRefinement(sim_stop.views, sim_stop.rig, ReconstructOptions{}, Deadline::Infinite());
    if (!matched.ok()) return {};
    rig = matched->rig;
    if (!matched->refined_views.empty()) views = matched->refined_views;
  }
  const auto scored = ScoreCandidates(views, rig, {}, Deadline::Infinite());
  TrainingStop stop;
  if (!scored.ok()) return stop;
  for (const ScoredCandidate& c : *scored) {
    const bool right = IsRightMatch(c.fit.points, truth);
    stop.two_view.push_back({c.two_view_features, right});
    if (c.multi_view) stop.multi_view.push_back({c.features, right});
  }
  return stop;
}

// The degraded stop of vineyard `seed` (SimulatedStop) labelled as above.
TrainingStop MakeTrainingStop(uint64_t seed) { return MakeTrainingStop(MakeSimulatedStop(seed)); }

// The stop of vineyard `seed` from input `input`: "synthetic" (MakeSimulatedStop), "labels" or
// "images" (MakeRenderedStop: the real 2D stage on label images or on segmented images, with the
// platform's fiducials when `fiducials`). VB_RIG_CAMERAS=4 renders with the four-camera study rig
// (sim::RigOptions::camera_count; docs/simulator.md, "A fourth camera").
SimulatedStop MakeStop(const std::string& input, uint64_t seed, bool fiducials = false) {
  if (input == "synthetic") return MakeSimulatedStop(seed);
  sim::RigOptions rig;
  if (const char* cameras = std::getenv("VB_RIG_CAMERAS")) rig.camera_count = std::atoi(cameras);
  return MakeRenderedStop(seed, input == "images", fiducials, rig);
}

// Comma-separated list in the environment variable `name`, or `fallback`.
std::vector<std::string> EnvList(const char* name, const std::string& fallback) {
  const char* env = std::getenv(name);
  std::string text = env ? env : fallback;
  std::vector<std::string> out;
  for (size_t begin = 0; begin <= text.size();) {
    size_t end = text.find(',', begin);
    if (end == std::string::npos) end = text.size();
    if (end > begin) out.push_back(text.substr(begin, end - begin));
    begin = end + 1;
  }
  return out;
}

// Area under the ROC curve of `probability` on `examples`.
double Auc(const std::vector<LabelledMatch>& examples,
           const std::function<double(const MatchFeatures&)>& probability) {
  std::vector<std::pair<double, bool>> scored;
  for (const LabelledMatch& e : examples) scored.push_back({probability(e.features), e.right});
  std::sort(scored.begin(), scored.end());
  double rank_sum = 0.0, positives = 0.0;
  for (size_t i = 0; i < scored.size(); ++i) {
    if (scored[i].second) {
      rank_sum += static_cast<double>(i + 1);
      positives += 1.0;
    }
  }
  const double negatives = scored.size() - positives;
  if (positives == 0 || negatives == 0) return 0.5;
  return (rank_sum - positives * (positives + 1) / 2) / (positives * negatives);
}

double Auc(const std::vector<LabelledMatch>& examples, const MatchFeatures& weights) {
  return Auc(examples, [&](const MatchFeatures& f) { return MatchProbability(f, weights); });
}

double Auc(const std::vector<LabelledMatch>& examples, const QuadraticLogistic& model) {
  return Auc(examples, [&](const MatchFeatures& f) { return model.Probability(f); });
}

void PrintWeights(const char* name, const MatchFeatures& w) {
  std::printf("  c.%s = {", name);
  for (int i = 0; i < kMatchFeatureCount; ++i) std::printf("%s%.4f", i ? ", " : "", w[i]);
  std::printf("};\n");
}

TEST(MatchClassifier, DefaultWeightsAreFinite) {
  const MatchClassifier c = DefaultMatchClassifier();
  EXPECT_TRUE(c.Validate().ok()) << c.Validate();
  EXPECT_FALSE(c.multi_view_quadratic.empty());
  for (int i = 0; i < kMatchFeatureCount; ++i) {
    EXPECT_TRUE(std::isfinite(c.multi_view[i]));
    EXPECT_TRUE(std::isfinite(c.two_view[i]));
  }
}

// One cane 14 degrees from the horizontal pair's epipolar lines, view 1's skeleton moved
// `shift_px` across itself (as near a junction), so that the pair (0, 1) puts it ~1 cm deep; and,
// when `other_cane_in_view_2`, view 2 shows only a different cane 3 cm higher.
std::vector<View2D> IllConditionedViews(const RigCalibration& rig, double shift_px,
                                        bool other_cane_in_view_2) {
  const auto one_cane = [](double z0, double z1) {
    VineModel model;
    Cane cane;
    cane.id = CaneId(1);
    cane.kind = CaneKind::kTrunk;
    cane.polyline.points = {{-0.12, 0.80, z0}, {0.12, 0.80, z1}};
    cane.polyline.radii = {0.004, 0.004};
    model.canes.push_back(cane);
    return model;
  };
  std::vector<View2D> views = SyntheticViews(one_cane(1.00, 1.06), rig);
  Segment2D& shifted = views[1].segments.at(0);
  const Eigen::Vector2d along = (shifted.points.back() - shifted.points.front()).normalized();
  for (Eigen::Vector2d& q : shifted.points) q += shift_px * Eigen::Vector2d(-along.y(), along.x());
  if (other_cane_in_view_2) views[2] = SyntheticViews(one_cane(1.03, 1.09), rig)[2];
  return views;
}

// The features of the longest candidate of pair (0, 1) scored with `options`.
MatchFeatures LongestOfPair01(const std::vector<View2D>& views, const RigCalibration& rig,
                              const CorrespondenceOptions& options) {
  const auto scored = ScoreCandidates(views, rig, options, Deadline::Infinite());
  EXPECT_TRUE(scored.ok()) << scored.status();
  const ScoredCandidate* best = nullptr;
  for (const ScoredCandidate& c : scored.value()) {
    if (c.candidate.view_a != 0 || c.candidate.view_b != 1) continue;
    if (!best || c.candidate.hits.size() > best->candidate.hits.size()) best = &c;
  }
  EXPECT_NE(best, nullptr);
  return best ? best->features : MatchFeatures{};
}

// Features 19-21 say how the refinement in the other view moves a candidate: a right match of
// an ill-conditioned pair is moved ~1 cm onto its cane, and is nearer the third view's
// centreline after it; where the third view shows another cane nothing is refined, and the first pass (no
// refinement) measures nothing.
TEST(MatchClassifier, RefinementFeaturesTellWhetherTheThirdViewAgrees) {
  const RigCalibration rig = sim::MakeRig(sim::RigOptions{}).value();
  CorrespondenceOptions options;
  const MatchFeatures moved = LongestOfPair01(IllConditionedViews(rig, 0.75, false), rig, options);
  std::printf("[ refinement ] kept %.0f, shift %.1f mm, centreline distance %.2f px closer\n",
              moved[19], 5.0 * std::expm1(moved[20]), 10.0 * moved[21]);
  EXPECT_EQ(moved[19], 1.0);
  EXPECT_GT(moved[20], std::log1p(0.004 / 0.005));  // moved by more than 4 mm
  EXPECT_GT(moved[21], 0.1);  // 1 px nearer view 2's centreline
  // Without the shift the pair is right already: kept, hardly moved.
  const MatchFeatures right = LongestOfPair01(IllConditionedViews(rig, 0.0, false), rig, options);
  EXPECT_EQ(right[19], 1.0);
  EXPECT_LT(right[20], std::log1p(0.002 / 0.005));
  EXPECT_LT(std::abs(right[21]), 0.1);
  // View 2 shows another cane: nothing associated, nothing kept.
  const MatchFeatures other = LongestOfPair01(IllConditionedViews(rig, 0.75, true), rig, options);
  EXPECT_EQ(other[19], 0.0);
  EXPECT_EQ(other[20], 0.0);
  EXPECT_EQ(other[21], 0.0);
  // The first pass does not refine, so nothing is measured.
  options.other_views.rounds = 0;
  const MatchFeatures first = LongestOfPair01(IllConditionedViews(rig, 0.75, false), rig, options);
  EXPECT_EQ(first[19], 0.0);
  EXPECT_EQ(first[20], 0.0);
  EXPECT_EQ(first[21], 0.0);
}

TEST(MatchClassifier, TrainingRecoversASeparatingDirection) {
  std::vector<LabelledMatch> examples;
  Noise noise(3);
  for (int i = 0; i < 400; ++i) {
    LabelledMatch e;
    e.features[0] = 1.0;
    e.features[2] = noise.Gaussian();
    e.features[12] = noise.Gaussian();
    e.right = 2.0 * e.features[12] - 1.5 * e.features[2] + 0.3 * noise.Gaussian() > 0.0;
    examples.push_back(e);
  }
  const auto w = TrainMatchClassifier(examples, {.l2 = 0.01});
  ASSERT_TRUE(w.ok()) << w.status();
  EXPECT_GT((*w)[12], 0.0);
  EXPECT_LT((*w)[2], 0.0);
  EXPECT_NEAR((*w)[12] / (*w)[2], -2.0 / 1.5, 0.4);
  EXPECT_GT(Auc(examples, *w), 0.97);
}

TEST(MatchClassifier, TrainingRejectsOneClassOrNaN) {
  std::vector<LabelledMatch> examples(3);
  for (auto& e : examples) e.features[0] = 1.0;
  EXPECT_EQ(TrainMatchClassifier(examples).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(TrainMatchClassifier({}).status().code(), absl::StatusCode::kInvalidArgument);
  examples[0].right = true;
  examples[1].features[3] = NAN;
  EXPECT_EQ(TrainMatchClassifier(examples).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(MatchClassifier, IsRightMatchNeedsOneCane) {
  Polyline3 a, b;
  a.points = {{0, 0, 0}, {1, 0, 0}};
  b.points = {{0, 0.05, 0}, {1, 0.05, 0}};
  a.radii = b.radii = {0.01, 0.01};
  std::vector<Eigen::Vector3d> on_a = {{0.1, 0.005, 0}, {0.5, -0.005, 0}, {0.9, 0, 0.003}};
  EXPECT_TRUE(IsRightMatch(on_a, {&a, &b}));
  std::vector<Eigen::Vector3d> split = {{0.1, 0.0, 0}, {0.5, 0.05, 0}};  // half on each
  EXPECT_FALSE(IsRightMatch(split, {&a, &b}));
  EXPECT_FALSE(IsRightMatch({}, {&a}));
}

// The committed weights separate right from wrong candidates on stops they were not trained on:
// rendered and segmented as the bench renders them (fiducials included), the candidates of the
// pipeline's second pass, as in training (seeds 1990-1991; the training used 1000-1099).
TEST(MatchClassifier, DefaultWeightsSeparateHeldOutCandidates) {
  std::vector<LabelledMatch> multi, two;
  for (uint64_t seed : {1990, 1991}) {
    const SimulatedStop sim_stop = MakeStop("images", seed, /*fiducials=*/true);
    ASSERT_FALSE(sim_stop.views.empty());
    TrainingStop stop = MakeTrainingStop(sim_stop, /*refined=*/true);
    multi.insert(multi.end(), stop.multi_view.begin(), stop.multi_view.end());
    two.insert(two.end(), stop.two_view.begin(), stop.two_view.end());
  }
  const MatchClassifier c = DefaultMatchClassifier();
  const double auc_multi = Auc(multi, c.multi_view);
  const double auc_quadratic = Auc(multi, c.multi_view_quadratic);
  const double auc_two = Auc(two, c.two_view);
  std::printf("[ held-out AUC ] multi-view %.3f (quadratic %.3f) over %zu candidates, two-view "
              "%.3f\n", auc_multi, auc_quadratic, multi.size(), auc_two);
  EXPECT_GT(auc_multi, 0.95);
  EXPECT_GT(auc_quadratic, 0.95);
  EXPECT_GT(auc_two, 0.9);
}

// On the degraded synthetic stops (SimulatedStop: drawn views, broken canes, the rig 1 px off,
// first-pass candidates), which the weights were not trained on, they still separate.
TEST(MatchClassifier, DefaultWeightsSeparateDegradedSyntheticCandidates) {
  std::vector<LabelledMatch> multi, two;
  for (uint64_t seed : {1990, 1991}) {
    TrainingStop stop = MakeTrainingStop(seed);
    multi.insert(multi.end(), stop.multi_view.begin(), stop.multi_view.end());
    two.insert(two.end(), stop.two_view.begin(), stop.two_view.end());
  }
  const MatchClassifier c = DefaultMatchClassifier();
  const double auc_multi = Auc(multi, c.multi_view);
  const double auc_two = Auc(two, c.two_view);
  std::printf("[ degraded AUC ] multi-view %.3f over %zu candidates, two-view %.3f\n", auc_multi,
              multi.size(), auc_two);
  EXPECT_GT(auc_multi, 0.85);
  EXPECT_GT(auc_two, 0.8);
}

// The tool that produced DefaultMatchClassifier(): run with
//   VB_TRAIN_INPUT=labels,images vb_reconstruct_test --gtest_also_run_disabled_tests
//       --gtest_filter=MatchClassifier.DISABLED_TrainOnSimulatedStops   (one command line)
// VB_TRAIN_INPUT: comma-separated inputs of MakeStop (default labels,images); VB_TRAIN_STOPS:
// stops per input, seeds 1000 onwards (default 100); VB_DEV_STOPS: held-out stops per input from
// seed 1100 on which alpha is reported (default 10); VB_TRAIN_PASS: "second" (default: the
// candidates of the pass after the rig refinement, as the bench renders them, with the
// platform's fiducials) or "first" (the rig as calibrated, no fiducials: the weights before
// 2026-11-22).
TEST(MatchClassifier, DISABLED_TrainOnSimulatedStops) {
  const char* env = std::getenv("VB_TRAIN_STOPS");
  const int stops = env ? std::atoi(env) : 100;
  const char* dev_env = std::getenv("VB_DEV_STOPS");
  const int held_out = dev_env ? std::atoi(dev_env) : 10;
  const std::vector<std::string> inputs = EnvList("VB_TRAIN_INPUT", "labels,images");
  const char* pass_env = std::getenv("VB_TRAIN_PASS");
  const bool second = !pass_env || std::string(pass_env) != "first";
  // VB_MATCH_DUMP=path: the multi-view candidates also written there as CSV, one per line
  // (seed, 1 for images, 1 if right, the features) for offline model comparisons
  // (scripts/match_model_heldout.cc).
  const char* dump_path = std::getenv("VB_MATCH_DUMP");
  FILE* dump = dump_path != nullptr ? std::fopen(dump_path, "w") : nullptr;
  ASSERT_TRUE(dump_path == nullptr || dump != nullptr) << "cannot write " << dump_path;
  std::vector<LabelledMatch> multi, two;
  for (const std::string& input : inputs) {
    for (int k = 0; k < stops; ++k) {
      const SimulatedStop sim_stop = MakeStop(input, 1000 + k, second);
      if (sim_stop.views.empty()) continue;
      TrainingStop stop = MakeTrainingStop(sim_stop, second);
      std::printf("%s %d: %zu candidates\n", input.c_str(), 1000 + k, stop.two_view.size());
      std::fflush(stdout);
      for (const LabelledMatch& e : stop.multi_view) {
        if (dump == nullptr) break;
        std::fprintf(dump, "%d,%d,%d", 1000 + k, input == "images" ? 1 : 0, e.right ? 1 : 0);
        for (double f : e.features) std::fprintf(dump, ",%.9g", f);
        std::fprintf(dump, "\n");
      }
      multi.insert(multi.end(), stop.multi_view.begin(), stop.multi_view.end());
      two.insert(two.end(), stop.two_view.begin(), stop.two_view.end());
    }
  }
  int right = 0;
  for (const auto& e : multi) right += e.right ? 1 : 0;
  if (dump != nullptr) std::fclose(dump);
  std::printf("seeds 1000-%d: %zu multi-view candidates (%d right), %zu two-view\n",
              1000 + stops - 1, multi.size(), right, two.size());
  const auto w_multi = TrainMatchClassifier(multi);
  const auto w_two = TrainMatchClassifier(two);
  ASSERT_TRUE(w_multi.ok()) << w_multi.status();
  ASSERT_TRUE(w_two.ok()) << w_two.status();
  std::printf("training AUC multi %.3f two %.3f\n", Auc(multi, *w_multi), Auc(two, *w_two));
  const MatchClassifier current = second ? DefaultMatchClassifier() : CalibratedRigMatchClassifier();
  std::printf("the committed weights on these candidates: AUC multi %.3f two %.3f\n",
              Auc(multi, current.multi_view), Auc(two, current.two_view));
  PrintWeights("multi_view", *w_multi);
  PrintWeights("two_view", *w_two);
  // VB_TRAIN_QUADRATIC=L2: also the quadratic model of the multi-view candidates (features
  // 1-21, ridge L2), printed as the body of DefaultQuadraticMatchModel.
  if (const char* quadratic = std::getenv("VB_TRAIN_QUADRATIC"); quadratic != nullptr) {
    std::vector<std::vector<double>> rows;
    std::vector<bool> labels;
    for (const LabelledMatch& e : multi) {
      rows.emplace_back(e.features.begin(), e.features.end());
      labels.push_back(e.right);
    }
    std::vector<int> index;
    for (int k = 1; k < kMatchFeatureCount; ++k) index.push_back(k);
    const auto model = TrainQuadraticLogistic(rows, labels, index, std::atof(quadratic));
    ASSERT_TRUE(model.ok()) << model.status();
    std::printf("quadratic (ridge %s): training AUC %.4f\n", quadratic, Auc(multi, *model));
    std::printf("%s", QuadraticLogisticSource(*model, "model").c_str());
  }
  // Held-out stops (seeds 1100 onwards): coverage and precision of the selected pieces
  // (correspondence_test_util.h Evaluate) for a range of alpha.
  CorrespondenceOptions options;
  options.classifier.multi_view = *w_multi;
  options.classifier.two_view = *w_two;
  for (const std::string& input : inputs) {
    std::vector<SimulatedStop> dev;
    for (int k = 0; k < held_out; ++k) dev.push_back(MakeStop(input, 1100 + k, second));
    for (double alpha : {0.5, 1.0, 2.0, 3.0, 5.0}) {
      options.alpha = alpha;
      double coverage = 0.0, precision = 0.0;
      for (const SimulatedStop& stop : dev) {
        if (stop.views.empty()) continue;
        const auto pieces = MatchSegments(stop.views, stop.rig, options, Deadline::Infinite());
        ASSERT_TRUE(pieces.ok()) << pieces.status();
        const Metrics m = Evaluate(*pieces, stop.scene.vine, stop.drawn, stop.true_rig);
        coverage += m.coverage / held_out;
        precision += m.precision / held_out;
      }
      std::printf("%s alpha %.1f: held-out coverage %.3f precision %.3f\n", input.c_str(), alpha,
                  coverage, precision);
    }
  }
}

}  // namespace
}  // namespace vb::reconstruct
