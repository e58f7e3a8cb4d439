// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/join_classifier.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <tuple>
#include <vector>

#include "gtest/gtest.h"
#include "workers/reconstruct/connect.h"
#include "workers/reconstruct/connect_test_util.h"
#include "workers/reconstruct/correspondence_test_util.h"
#include "workers/reconstruct/join_images.h"
#include "workers/reconstruct/join_test_util.h"
#include "workers/reconstruct/reconstruct.h"

namespace vb::reconstruct {
namespace {

using connect_test::Line;

double Probability(const Polyline3& child, bool base_is_last, const Polyline3& parent,
                   const Eigen::Vector3d& head_centre = {0, 0.8, 1.0}) {
  JoinGeometry g;
  g.child = &child;
  g.base_is_last = base_is_last;
  g.parent = &parent;
  const Eigen::Vector3d base = base_is_last ? child.points.back() : child.points.front();
  double gap = 0.0;
  g.point = parent.PointAt(parent.Project(base, &gap));
  g.gap_m = gap;
  g.head_centre = head_centre;
  g.base_to_head_m = std::max(0.0, (base - head_centre).norm() - 0.05);
  g.point_to_head_m = std::max(0.0, (g.point - head_centre).norm() - 0.05);
  return JoinProbability(ComputeJoinFeatures(g), DefaultJoinWeights());
}

// The default weights carry the committed quadratic models on their documented features, and a
// broken model is rejected naming it.
TEST(JoinClassifier, DefaultWeightsHoldValidQuadraticModels) {
  JoinWeights w = DefaultJoinWeights();
  ASSERT_TRUE(w.Validate().ok()) << w.Validate();
  EXPECT_EQ(w.cane_quadratic.index, QuadraticJoinFeatures(false));
  EXPECT_EQ(w.root_quadratic.index, QuadraticJoinFeatures(true));
  EXPECT_EQ(w.cane_quadratic.index.size(), 14u);
  EXPECT_EQ(w.root_quadratic.index.size(), 11u);
  w.root_quadratic.sd[2] = -1.0;
  ConnectOptions options;
  options.join_weights = w;
  const absl::Status s = options.Validate();
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("join_weights.root_quadratic"), std::string::npos) << s;
  EXPECT_TRUE(ImageJoinWeights().cane_quadratic.empty());  // the image weights stay linear
}

// A piece continuing another beyond a gap: the wider the gap, and the more the piece bends away
// from the line of its parent, the less likely the join. (Whether a continuation beats a cane
// the piece touches at a crossing is decided in context: ConnectCanes' crossing test.)
TEST(JoinClassifier, WiderGapsAndBendsAreLessLikely) {
  const Polyline3 inner = Line({0.06, 0.8, 1.0}, {0.40, 0.8, 1.0});
  const Polyline3 near = Line({0.41, 0.8, 1.0}, {0.80, 0.8, 1.0});
  const Polyline3 far = Line({0.46, 0.8, 1.0}, {0.85, 0.8, 1.0});
  const Polyline3 bent = Line({0.41, 0.8, 1.0}, {0.41 + 0.39 * 0.5, 0.8, 1.0 + 0.39 * 0.866});
  EXPECT_GT(Probability(near, false, inner), Probability(far, false, inner));
  EXPECT_GT(Probability(near, false, inner), Probability(bent, false, inner));
  EXPECT_GT(Probability(near, false, inner), ConnectOptions().min_join_probability);
}

// The end nearer the head is the base: the same join read backwards is less likely.
TEST(JoinClassifier, TheBaseIsTheEndNearerTheHead) {
  const Polyline3 parent = Line({0.06, 0.8, 1.0}, {0.5, 0.8, 1.05}, 0.006);
  const Polyline3 child = Line({0.3, 0.8, 1.036}, {0.35, 0.8, 1.4}, 0.004);  // 2 mm off
  EXPECT_GT(Probability(child, false, parent), 3.0 * Probability(child, true, parent));
}

TEST(JoinClassifier, FeaturesAreFiniteForDegenerateGeometry) {
  const Polyline3 child = Line({0, 0.8, 1.0}, {0, 0.8, 1.0 + 1e-9});
  JoinGeometry g;
  g.child = &child;
  g.target = JoinTarget::kHead;
  g.head_centre = child.points.front();
  for (double v : ComputeJoinFeatures(g)) EXPECT_TRUE(std::isfinite(v));
}

// The image features: the evidence as given, the unsupported part of the gap, and crossing
// evidence for joins to a cane only; all 0 without images.
TEST(JoinClassifier, ImageFeaturesCarryTheEvidenceAndAreZeroWithoutImages) {
  const Polyline3 parent = Line({0.06, 0.8, 1.0}, {0.5, 0.8, 1.0});
  const Polyline3 child = Line({0.3, 0.8, 1.03}, {0.3, 0.8, 1.4});
  JoinGeometry g;
  g.child = &child;
  g.parent = &parent;
  g.point = {0.3, 0.8, 1.0};
  g.gap_m = 0.03;
  const JoinFeatures none = ComputeJoinFeatures(g);
  for (int i = kFirstImageJoinFeature; i < kJoinFeatureCount; ++i) EXPECT_EQ(none[i], 0.0) << i;
  const JoinImageEvidence e{0.25, 0.75, 0.5, 0.6};
  g.images = &e;
  const JoinFeatures f = ComputeJoinFeatures(g);
  EXPECT_DOUBLE_EQ(f[17], 0.25);
  EXPECT_DOUBLE_EQ(f[18], 0.75);
  EXPECT_DOUBLE_EQ(f[19], (1.0 - 0.75) * 0.03 / 0.02);
  EXPECT_DOUBLE_EQ(f[20], 0.5);
  EXPECT_DOUBLE_EQ(f[21], 0.6);
  for (int i = 0; i < kFirstImageJoinFeature; ++i) EXPECT_EQ(f[i], none[i]) << i;
  g.target = JoinTarget::kTrunk;
  const JoinFeatures root = ComputeJoinFeatures(g);
  EXPECT_DOUBLE_EQ(root[18], 0.75);
  EXPECT_EQ(root[21], 0.0);  // crossing a cane: not for the trunk or head
}

// The weights trained with the images: a gap the images show as wood makes a join likelier, and
// wood beyond the parent along the child's line (a crossing) makes it less likely.
TEST(JoinClassifier, ImageWeightsFavourSeenGapsAndDisfavourCrossings) {
  const Polyline3 parent = Line({0.06, 0.8, 1.0}, {0.5, 0.8, 1.0}, 0.006);
  const Polyline3 child = Line({0.3, 0.8, 1.02}, {0.35, 0.8, 1.4}, 0.004);
  JoinGeometry g;
  g.child = &child;
  g.parent = &parent;
  g.point = {0.3, 0.8, 1.0};
  g.gap_m = 0.02;
  g.head_centre = {0, 0.8, 1.0};
  g.base_to_head_m = 0.25;
  g.point_to_head_m = 0.25;
  const JoinWeights w = ImageJoinWeights();
  EXPECT_TRUE(UsesImageFeatures(w));
  EXPECT_FALSE(UsesImageFeatures(DefaultJoinWeights()));
  const JoinImageEvidence seen{1.0, 1.0, 0.0, 0.0}, unseen{0.0, 0.1, 0.0, 0.0};
  const JoinImageEvidence crossing{1.0, 1.0, 0.0, 1.0};
  g.images = &seen;
  const double p_seen = JoinProbability(ComputeJoinFeatures(g), w);
  g.images = &unseen;
  const double p_unseen = JoinProbability(ComputeJoinFeatures(g), w);
  g.images = &crossing;
  const double p_crossing = JoinProbability(ComputeJoinFeatures(g), w);
  EXPECT_GT(p_seen, 2.0 * p_unseen);
  EXPECT_GT(p_seen, 2.0 * p_crossing);
}

TEST(JoinClassifier, UsesImageFeaturesOnlyWithAWeightOnOne) {
  JoinWeights w;
  w.cane[1] = w.root[16] = 1.0;
  EXPECT_FALSE(UsesImageFeatures(w));
  w.root[kJoinFeatureCount - 1] = -0.5;
  EXPECT_TRUE(UsesImageFeatures(w));
  w = JoinWeights{};
  w.cane[kFirstImageJoinFeature] = 0.1;
  EXPECT_TRUE(UsesImageFeatures(w));
}

// Connection measures the images of every candidate join when given them, and of none when the
// weights do not use them.
TEST(JoinClassifier, ConnectionLooksTheImagesUpOnlyForWeightsThatUseThem) {
  const Polyline3 trunk = Line({0, 0.8, 0}, {0, 0.8, 0.95}, 0.025);
  const Polyline3 parent = Line({0.06, 0.8, 1.0}, {0.5, 0.8, 1.0}, 0.006);
  const Polyline3 child = Line({0.3, 0.8, 1.0}, {0.3, 0.8, 1.3});  // from the parent, upward
  const HeadModel head = connect_test::Head();
  int calls = 0;
  const JoinImageFn images = [&](const Eigen::Vector3d&, const Eigen::Vector3d&) {
    ++calls;
    return JoinImageEvidence{0.9, 0.4, 1.0, 0.7};
  };
  ConnectOptions options;
  const auto prepared = PrepareCanes({parent, child}, trunk, head, options);
  ASSERT_TRUE(prepared.ok());
  ASSERT_EQ(prepared->canes.size(), 2u);
  const std::vector<JoinCandidate> joins = FindJoins(*prepared, head, options, images);
  bool checked_fork = false;
  for (const JoinCandidate& j : joins) {
    EXPECT_EQ(j.features[17], 0.9);
    EXPECT_EQ(j.features[18], 0.4);
    EXPECT_EQ(j.features[20], 1.0);
    // Crossing evidence is measured, not taken from the function's past_support.
    if (j.target != JoinTarget::kCane) {
      EXPECT_EQ(j.features[21], 0.0);
    }
    if (j.child == 1 && !j.base_is_last && j.parent == 0) {
      // The child's line continued downward past its parent: wood by the function's word.
      EXPECT_EQ(j.features[21], 0.9);
      checked_fork = true;
    }
  }
  EXPECT_TRUE(checked_fork);
  EXPECT_GT(calls, 0);
  for (const JoinCandidate& j : FindJoins(*prepared, head, options)) {
    for (int i = kFirstImageJoinFeature; i < kJoinFeatureCount; ++i) EXPECT_EQ(j.features[i], 0);
  }
  calls = 0;
  for (int i = kFirstImageJoinFeature; i < kJoinFeatureCount; ++i)
    options.join_weights.cane[i] = options.join_weights.root[i] = 0.0;
  ASSERT_TRUE(ConnectCanes({parent, child}, trunk, head, options, nullptr, {}, images).ok());
  EXPECT_EQ(calls, 0);
  options.join_weights.cane[20] = 0.5;
  ASSERT_TRUE(ConnectCanes({parent, child}, trunk, head, options, nullptr, {}, images).ok());
  EXPECT_GT(calls, 0);
}

TEST(JoinClassifier, TrainingSeparatesSeparableJoinsAndRejectsBadExamples) {
  std::vector<LabelledJoin> examples;
  for (int i = 0; i < 200; ++i) {
    LabelledJoin e;
    e.features[0] = 1.0;
    e.features[1] = (i % 20) / 10.0;  // gap: right joins are the near ones, with label noise
    e.right = e.features[1] < 0.9 ? (i % 17 != 0) : (i % 13 == 0);
    examples.push_back(e);
  }
  const auto w = TrainJoinClassifier(examples);
  ASSERT_TRUE(w.ok()) << w.status();
  EXPECT_LT((*w)[1], 0.0);  // the wider the gap, the less likely
  EXPECT_EQ(TrainJoinClassifier({}).status().code(), absl::StatusCode::kInvalidArgument);
  std::vector<LabelledJoin> one_label(3);
  EXPECT_EQ(TrainJoinClassifier(one_label).status().code(), absl::StatusCode::kInvalidArgument);
  examples[5].features[3] = std::nan("");
  EXPECT_EQ(TrainJoinClassifier(examples).status().code(), absl::StatusCode::kInvalidArgument);
}

// --- Training tool -------------------------------------------------------------------------

double Auc(const std::vector<LabelledJoin>& examples, const JoinWeights& w) {
  std::vector<std::pair<double, bool>> scored;
  for (const LabelledJoin& e : examples) scored.push_back({JoinProbability(e.features, w), e.right});
  std::sort(scored.begin(), scored.end());
  double rank_sum = 0.0, positives = 0.0;
  for (size_t i = 0; i < scored.size(); ++i) {
    if (scored[i].second) rank_sum += static_cast<double>(i + 1), positives += 1;
  }
  const double negatives = static_cast<double>(scored.size()) - positives;
  return (rank_sum - positives * (positives + 1) / 2) / std::max(1.0, positives * negatives);
}

// The tool that produced DefaultJoinWeights(): run with
//   VB_TRAIN_STOPS=100 vb_reconstruct_test --gtest_also_run_disabled_tests
//       --gtest_filter=JoinClassifier.DISABLED_TrainOnSimulatedStops   (one command line)
// Candidate joins of the real pipeline (ExtractStructure on the renderer's label images and on
// the segmenter's output, correspondence, assembly, head) on training seeds 1000 onwards,
// rendered with the platform's fiducials as the bench renders them, labelled against the true
// vine (LabelJoins).
TEST(JoinClassifier, DISABLED_TrainOnSimulatedStops) {
  const char* env = std::getenv("VB_TRAIN_STOPS");
  const int stops = env ? std::atoi(env) : 100;
  const ReconstructOptions options;
  std::vector<LabelledJoin> examples;
  // VB_JOIN_DUMP=path: the labelled joins also written there as CSV (offline model comparison,
  // docs/reconstruction.md section 6, "Joins: the oracle's bound and a nonlinear classifier").
  const char* dump_path = std::getenv("VB_JOIN_DUMP");
  FILE* dump = dump_path != nullptr ? std::fopen(dump_path, "w") : nullptr;
  ASSERT_TRUE(dump_path == nullptr || dump != nullptr) << "cannot write " << dump_path;
  // VB_TRAIN_INPUT=labels|images: one input only (both by default).
  const char* only = std::getenv("VB_TRAIN_INPUT");
  for (bool images : {false, true}) {
    if (only != nullptr && std::string(only) != (images ? "images" : "labels")) continue;
    for (int k = 0; k < stops; ++k) {
      const SimulatedStop stop = MakeRenderedStop(1000 + k, images, /*fiducials=*/true);
      if (stop.views.empty()) continue;
      const Deadline deadline = Deadline::Infinite();
      // Correspondence with the rig refined in between, as the pipeline does it.
      const auto matched = MatchWithRigRefinement(stop.views, stop.rig, options, deadline);
      ASSERT_TRUE(matched.ok()) << matched.status();
      auto canes = AssembleCanes(matched->pieces, options.assembly, deadline);
      ASSERT_TRUE(canes.ok()) << canes.status();
      std::erase_if(*canes,
                    [&](const Polyline3& cane) { return options.volume.MostlyOutside(cane); });
      std::vector<Eigen::Vector3d> hints;
      for (const Polyline3& c : *canes) hints.insert(hints.end(), c.points.begin(), c.points.end());
      const auto head = ReconstructHeadAndTrunk(stop.views, matched->rig, options.volume,
                                                options.head, deadline, hints);
      ASSERT_TRUE(head.ok()) << head.status();
      const auto prepared = PrepareCanes(*canes, head->trunk, head->head, options.connect);
      ASSERT_TRUE(prepared.ok()) << prepared.status();
      const JoinImageFn join_images = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
        return MeasureJoinImages(a, b, stop.views, matched->rig);
      };
      const std::vector<JoinCandidate> joins =
          FindJoins(*prepared, head->head, options.connect, join_images);
      const std::vector<LabelledJoin> labelled = LabelJoins(*prepared, joins, stop.scene.vine);
      examples.insert(examples.end(), labelled.begin(), labelled.end());
      if (dump != nullptr) {
        // One line per join: seed, input (0 labels, 1 images), label, the features.
        for (const LabelledJoin& e : labelled) {
          std::fprintf(dump, "%d,%d,%d", 1000 + k, images ? 1 : 0, e.right ? 1 : 0);
          for (double v : e.features) std::fprintf(dump, ",%.6g", v);
          std::fprintf(dump, "\n");
        }
        std::fflush(dump);
      }
    }
  }
  if (dump != nullptr) std::fclose(dump);
  // Trained twice on the same joins: with the image features, and without them (a control:
  // what retraining alone gains on today's pipeline).
  for (bool with_images : {true, false}) {
    std::vector<LabelledJoin> to_cane, to_root;
    for (LabelledJoin e : examples) {
      if (!with_images) {
        std::fill(e.features.begin() + kFirstImageJoinFeature, e.features.end(), 0.0);
      }
      (e.features[3] != 0.0 || e.features[4] != 0.0 ? to_root : to_cane).push_back(e);
    }
    JoinWeights w;
    for (auto [name, set, out] : {std::tuple{"cane", &to_cane, &w.cane},
                                  std::tuple{"root", &to_root, &w.root}}) {
      int right = 0;
      for (const LabelledJoin& e : *set) right += e.right ? 1 : 0;
      const auto trained = TrainJoinClassifier(*set);
      ASSERT_TRUE(trained.ok()) << trained.status();
      *out = *trained;
      std::printf("seeds 1000-%d, labels and images, joins to a %s: %zu candidates, %d right\n",
                  1000 + stops - 1, name, set->size(), right);
    }
    JoinWeights committed = DefaultJoinWeights();
    committed.cane_quadratic = committed.root_quadratic = {};
    std::printf("%s image features: training AUC %.4f (committed linear weights %.4f)\n",
                with_images ? "with" : "without", Auc(examples, w), Auc(examples, committed));
    for (auto [name, v] : {std::pair{"cane", &w.cane}, std::pair{"root", &w.root}}) {
      std::printf("  w.%s = {", name);
      for (int i = 0; i < kJoinFeatureCount; ++i) std::printf("%s%.4f", i ? ", " : "", (*v)[i]);
      std::printf("};\n");
    }
  }
  // VB_TRAIN_QUADRATIC=L2: also the quadratic models (QuadraticJoinFeatures, ridge L2), printed
  // as the body of DefaultQuadraticJoinModels.
  if (const char* quadratic = std::getenv("VB_TRAIN_QUADRATIC"); quadratic != nullptr) {
    JoinWeights q;
    for (const bool root : {false, true}) {
      std::vector<std::vector<double>> rows;
      std::vector<bool> labels;
      for (const LabelledJoin& e : examples) {
        if ((e.features[3] != 0.0 || e.features[4] != 0.0) != root) continue;
        rows.emplace_back(e.features.begin(), e.features.end());
        labels.push_back(e.right);
      }
      const auto model = TrainQuadraticLogistic(rows, labels, QuadraticJoinFeatures(root),
                                                std::atof(quadratic));
      ASSERT_TRUE(model.ok()) << model.status();
      (root ? q.root_quadratic : q.cane_quadratic) = *model;
    }
    std::printf("quadratic (ridge %s): training AUC %.4f\n", quadratic, Auc(examples, q));
    std::printf("%s", QuadraticLogisticSource(q.cane_quadratic, "w.cane_quadratic").c_str());
    std::printf("%s", QuadraticLogisticSource(q.root_quadratic, "w.root_quadratic").c_str());
  }
}

}  // namespace
}  // namespace vb::reconstruct
