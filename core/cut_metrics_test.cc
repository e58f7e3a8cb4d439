// SPDX-License-Identifier: Apache-2.0
#include "core/cut_metrics.h"

#include <limits>
#include <string>
#include <vector>

#include "gtest/gtest.h"

namespace vb {
namespace {

Cane StraightCane(int64_t id, std::optional<int64_t> parent, CaneKind kind, Eigen::Vector3d base,
                  Eigen::Vector3d dir, double length) {
  Cane c;
  c.id = CaneId(id);
  if (parent) c.parent_id = CaneId(*parent);
  c.kind = kind;
  c.polyline.points = {base, base + dir.normalized() * length};
  c.polyline.radii = {0.005, 0.003};
  return c;
}

// Trunk 1 (50 mm thick) up to z = 1; cane 2 (kept) along +x; canes 3 and 4 (removed) along -x, 30 mm apart;
// cane 5 (a spur) along +y.
VineModel Truth() {
  VineModel v;
  v.canes.push_back(StraightCane(1, std::nullopt, CaneKind::kTrunk, {0, 0, 0}, {0, 0, 1}, 1.0));
  v.canes.back().polyline.radii = {0.025, 0.025};
  v.canes.push_back(StraightCane(2, 1, CaneKind::kCane, {0.05, 0, 1}, {1, 0, 0}, 0.8));
  v.canes.push_back(StraightCane(3, 1, CaneKind::kCane, {-0.05, 0, 1}, {-1, 0, 0}, 0.6));
  v.canes.push_back(StraightCane(4, 1, CaneKind::kCane, {-0.05, 0, 1.03}, {-1, 0, 0}, 0.6));
  v.canes.push_back(StraightCane(5, 1, CaneKind::kCane, {0, 0.05, 1}, {0, 1, 0}, 0.5));
  return v;
}

Cut MakeCut(int64_t id, int64_t cane, Eigen::Vector3d point, CutReason reason) {
  Cut c;
  c.id = CutId(id);
  c.cane_id = CaneId(cane);
  c.point = point;
  c.direction = Eigen::Vector3d::UnitX();
  c.diameter_m = 0.008;
  c.reason = reason;
  return c;
}

CutPlan TruthPlan() {
  CutPlan plan;
  plan.keep = {CaneId(2)};
  plan.spurs = {CaneId(5)};
  plan.cuts = {MakeCut(1, 2, {0.65, 0, 1}, CutReason::kShorten),
               MakeCut(2, 3, {-0.06, 0, 1}, CutReason::kRemove),
               MakeCut(3, 4, {-0.06, 0, 1.03}, CutReason::kRemove),
               MakeCut(4, 5, {0, 0.15, 1}, CutReason::kSpur)};
  return plan;
}

TEST(EvaluateCuts, IdenticalPlansAreExact) {
  const VineModel truth = Truth();
  const CutPlan plan = TruthPlan();
  auto m = EvaluateCuts(truth, plan, truth, &plan);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->truth_cuts, 4);
  EXPECT_EQ(m->model_cuts, 4);
  EXPECT_EQ(m->matched_cuts, 4);
  EXPECT_EQ(m->cut_error_median_m, 0.0);
  EXPECT_EQ(m->cut_error_p95_m, 0.0);
  EXPECT_EQ(m->cuts_missed_fraction, 0.0);
  EXPECT_EQ(m->cuts_spurious_fraction, 0.0);
  EXPECT_EQ(m->cuts_on_kept_canes, 0);
}

TEST(EvaluateCuts, ErrorsOverMatchedCutsAndMissesBeyondThirtyMillimetres) {
  const VineModel truth = Truth();
  const CutPlan truth_plan = TruthPlan();
  CutPlan model_plan = truth_plan;
  model_plan.cuts[0].point.x() += 0.010;  // shorten cut 10 mm further out: matched
  model_plan.cuts[1].point.x() -= 0.020;  // 20 mm: matched
  model_plan.cuts[2].point.x() -= 0.005;  // 5 mm: matched
  model_plan.cuts[3].point.y() += 0.040;  // spur cut 40 mm too long: missed and spurious
  auto m = EvaluateCuts(truth, truth_plan, truth, &model_plan);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->matched_cuts, 3);
  EXPECT_NEAR(m->cut_error_median_m, 0.010, 1e-9);
  EXPECT_NEAR(m->cut_error_p95_m, 0.010 + 0.9 * 0.010, 1e-9);  // position 1.9 of {5, 10, 20} mm
  EXPECT_DOUBLE_EQ(m->cuts_missed_fraction, 0.25);
  EXPECT_DOUBLE_EQ(m->cuts_spurious_fraction, 0.25);
  // Beyond the spur cut: wood the truth removes anyway, not a cut on a kept cane.
  EXPECT_EQ(m->cuts_on_kept_canes, 0);
}

TEST(EvaluateCuts, CutNearerAnotherCaneDoesNotMatch) {
  const VineModel truth = Truth();
  CutPlan truth_plan = TruthPlan();
  truth_plan.cuts.erase(truth_plan.cuts.begin() + 2);  // no truth cut on cane 4
  CutPlan model_plan = truth_plan;
  // 20 mm from the truth cut on cane 3 but 10 mm from cane 4's axis: assigned to cane 4.
  model_plan.cuts[1].point = {-0.06, 0, 1.02};
  auto m = EvaluateCuts(truth, truth_plan, truth, &model_plan);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->matched_cuts, 2);
  EXPECT_DOUBLE_EQ(m->cuts_missed_fraction, 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(m->cuts_spurious_fraction, 1.0 / 3.0);
}

TEST(EvaluateCuts, CutWithinTenMillimetresOfItsCaneMatchesThoughNearerAnother) {
  // Canes 3 and 4 leave the head 12 mm apart; the truth removes cane 3, and cane 4, growing from
  // it, falls with it.
  VineModel truth;
  truth.canes.push_back(StraightCane(1, std::nullopt, CaneKind::kTrunk, {0, 0, 0}, {0, 0, 1}, 1.0));
  truth.canes.push_back(StraightCane(3, 1, CaneKind::kCane, {-0.05, 0, 1}, {-1, 0, 0}, 0.6));
  truth.canes.push_back(StraightCane(4, 3, CaneKind::kCane, {-0.05, 0, 1.012}, {-1, 0, 0}, 0.6));
  CutPlan truth_plan;
  truth_plan.cuts = {MakeCut(1, 3, {-0.06, 0, 1}, CutReason::kRemove)};
  CutPlan model_plan = truth_plan;
  // 7 mm from cane 3's axis, 5 mm from cane 4's: nearest cane 4, yet on cane 3 and 7 mm from its
  // cut.
  model_plan.cuts[0].point = {-0.06, 0, 1.007};
  auto m = EvaluateCuts(truth, truth_plan, truth, &model_plan);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->matched_cuts, 1);
  EXPECT_NEAR(m->cut_error_median_m, 0.007, 1e-9);
  auto matching = MatchCuts(truth, truth_plan, truth, &model_plan);
  ASSERT_TRUE(matching.ok()) << matching.status();
  EXPECT_EQ(matching->truth_partner, std::vector<int>{0});
  EXPECT_EQ(matching->model_partner, std::vector<int>{0});
  EXPECT_EQ(matching->model_truth_cane, std::vector<size_t>{2});  // assigned to cane 4, nearest

  // A tighter tolerance takes it off cane 3.
  CutMetricsOptions tight;
  tight.on_cane_distance_m = 0.005;
  m = EvaluateCuts(truth, truth_plan, truth, &model_plan, tight);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->matched_cuts, 0);

  // 12 mm from cane 3's axis (on cane 4's): beyond the tolerance, not on cane 3.
  model_plan.cuts[0].point = {-0.06, 0, 1.012};
  m = EvaluateCuts(truth, truth_plan, truth, &model_plan);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->matched_cuts, 0);
  EXPECT_EQ(m->cuts_on_kept_canes, 0);

  // When the truth keeps cane 4 (growing from the trunk), the cut 5 mm from it would take kept
  // wood: it lies on cane 4 only, and counts as a cut on a kept cane.
  truth.canes[2].parent_id = CaneId(1);
  truth_plan.keep = {CaneId(4)};
  model_plan = truth_plan;
  model_plan.cuts[0].point = {-0.06, 0, 1.007};
  m = EvaluateCuts(truth, truth_plan, truth, &model_plan);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->matched_cuts, 0);
  EXPECT_EQ(m->cuts_on_kept_canes, 1);
}

TEST(EvaluateCuts, TheTenMillimetreRuleNeverTakesAPairTheNearestCaneMakes) {
  // Canes 3 and 4 leave the trunk 12 mm apart; the truth removes both. Model cut 0 lies 5 mm
  // from cane 3's axis (its nearest cane) and 7 mm from cane 4's, 9.4 mm from the cut on cane 3
  // and 7.3 mm from the cut on cane 4. Model cut 1 lies on cane 4's axis, 20 mm from its cut.
  VineModel truth;
  truth.canes.push_back(StraightCane(1, std::nullopt, CaneKind::kTrunk, {0, 0, 0}, {0, 0, 1}, 1.0));
  truth.canes.push_back(StraightCane(3, 1, CaneKind::kCane, {-0.05, 0, 1}, {-1, 0, 0}, 0.6));
  truth.canes.push_back(StraightCane(4, 1, CaneKind::kCane, {-0.05, 0, 1.012}, {-1, 0, 0}, 0.6));
  CutPlan truth_plan;
  truth_plan.cuts = {MakeCut(1, 3, {-0.06, 0, 1}, CutReason::kRemove),
                     MakeCut(2, 4, {-0.07, 0, 1.012}, CutReason::kRemove)};
  CutPlan model_plan = truth_plan;
  model_plan.cuts[0].point = {-0.068, 0, 1.005};
  model_plan.cuts[1].point = {-0.09, 0, 1.012};
  auto matching = MatchCuts(truth, truth_plan, truth, &model_plan);
  ASSERT_TRUE(matching.ok()) << matching.status();
  // Nearest first over both rules at once would pair cut 0 with cane 4's cut and leave cane 3's
  // unpaired; the nearest-cane pairs come first.
  EXPECT_EQ(matching->truth_partner, (std::vector<int>{0, 1}));
  EXPECT_EQ(matching->model_partner, (std::vector<int>{0, 1}));
  auto m = EvaluateCuts(truth, truth_plan, truth, &model_plan);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->matched_cuts, 2);
}

TEST(EvaluateCuts, OneReconstructedCutMatchesOneTruthCut) {
  const VineModel truth = Truth();
  const CutPlan truth_plan = TruthPlan();
  CutPlan model_plan = truth_plan;
  // A second cut 3 mm from the removal cut on cane 3: the nearer one matches, the other is spurious.
  model_plan.cuts.push_back(MakeCut(9, 3, {-0.063, 0, 1}, CutReason::kRemove));
  auto m = EvaluateCuts(truth, truth_plan, truth, &model_plan);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->matched_cuts, 4);
  EXPECT_EQ(m->cut_error_median_m, 0.0);
  EXPECT_DOUBLE_EQ(m->cuts_spurious_fraction, 0.2);
  EXPECT_EQ(m->cuts_on_kept_canes, 0);  // cane 3 is removed in the truth
}

TEST(EvaluateCuts, CountsCutsOnWoodTheTruthKeeps) {
  const VineModel truth = Truth();
  const CutPlan truth_plan = TruthPlan();
  CutPlan model_plan = truth_plan;
  int64_t id = 10;
  auto add = [&](int64_t cane, Eigen::Vector3d p) {
    model_plan.cuts.push_back(MakeCut(id++, cane, p, CutReason::kRemove));
  };
  add(2, {0.30, 0.0, 1.0});    // on the kept cane, before its shortening cut: counted
  add(2, {0.30, 0.008, 1.0});  // 8 mm from its axis: counted
  add(2, {0.30, 0.015, 1.0});  // 15 mm from its axis: a miss, not a cut on it
  add(2, {0.75, 0.0, 1.0});    // beyond the truth's shortening cut: removed wood anyway
  add(5, {0.0, 0.09, 1.0});    // on the spur, 60 mm short of its cut: counted
  add(1, {0.0, 0.0, 0.5});     // on the trunk (every kept cane falls): counted
  add(1, {0.02, 0.0, 0.4});    // 20 mm off the trunk's axis but inside its wood: counted
  add(1, {0.03, 0.0, 0.3});    // 30 mm off: outside the trunk, not counted
  auto m = EvaluateCuts(truth, truth_plan, truth, &model_plan);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->matched_cuts, 4);
  EXPECT_EQ(m->cuts_on_kept_canes, 5);
  EXPECT_DOUBLE_EQ(m->cuts_spurious_fraction, 8.0 / 12.0);
}

TEST(EvaluateCuts, NoReconstructedPlanMissesEveryTruthCut) {
  const VineModel truth = Truth();
  auto m = EvaluateCuts(truth, TruthPlan(), VineModel{}, nullptr);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->cuts_missed_fraction, 1.0);
  EXPECT_EQ(m->cuts_spurious_fraction, 0.0);
  EXPECT_EQ(m->model_cuts, 0);
  // An empty truth plan misses nothing.
  CutPlan empty_plan;
  m = EvaluateCuts(truth, empty_plan, VineModel{}, nullptr);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->cuts_missed_fraction, 0.0);
}

TEST(EvaluateCuts, RejectsInvalidInputNamingIt) {
  const VineModel truth = Truth();
  CutPlan bad = TruthPlan();
  bad.cuts[0].cane_id = CaneId(99);
  auto m = EvaluateCuts(truth, bad, truth, nullptr);
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(m.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(m.status().message().find("truth_plan"), std::string_view::npos) << m.status();
  const CutPlan plan = TruthPlan();
  m = EvaluateCuts(truth, plan, truth, &bad);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("model_plan"), std::string_view::npos) << m.status();
  VineModel broken = truth;
  broken.canes[2].parent_id = CaneId(42);
  m = EvaluateCuts(truth, plan, broken, &plan);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("model: canes[2]"), std::string_view::npos) << m.status();
  CutMetricsOptions options;
  options.match_distance_m = -1;
  m = EvaluateCuts(truth, plan, truth, &plan, options);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("match_distance_m"), std::string_view::npos) << m.status();
  options = {};
  options.on_cane_distance_m = std::numeric_limits<double>::quiet_NaN();
  m = EvaluateCuts(truth, plan, truth, &plan, options);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("on_cane_distance_m"), std::string_view::npos) << m.status();
}

TEST(CutMetricsToJson, HasTheDocumentedKeys) {
  const nlohmann::json j = CutMetricsToJson(CutMetrics{});
  for (const char* key : {"cut_error_median_m", "cut_error_p95_m", "cuts_missed_fraction",
                          "cuts_spurious_fraction", "cuts_on_kept_canes", "truth_cuts",
                          "model_cuts", "matched_cuts"})
    EXPECT_TRUE(j.contains(key)) << key;
}

}  // namespace
}  // namespace vb
