// SPDX-License-Identifier: Apache-2.0
#include "sim/expert_pruner.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/vine_generator.h"

namespace vb::sim {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

// A hand-built vine: trunk up to a head at (0, 0.8, 1.0), fruiting wire at z = 1.05. Head canes
// start on the head's surface at x = +-(0.05 + base_dx), base_dx <= 0.08.
class VineBuilder {
 public:
  VineBuilder() {
    Cane trunk;
    trunk.id = CaneId(1);
    trunk.kind = CaneKind::kTrunk;
    trunk.polyline.points = {{0, 0.8, 0}, {0, 0.8, 1.0}};
    trunk.polyline.radii = {0.02, 0.02};
    model_.canes.push_back(trunk);
    // A head 0.22 m wide along the row; its centre (mean of the sphere centres) is the trunk top.
    model_.head.spheres.push_back({Eigen::Vector3d(0, 0.8, 1.0), 0.05});
    model_.head.spheres.push_back({Eigen::Vector3d(-0.07, 0.8, 1.0), 0.04});
    model_.head.spheres.push_back({Eigen::Vector3d(0.07, 0.8, 1.0), 0.04});
    Wire wire;
    wire.id = WireId(1);
    wire.points = {{-2.5, 0.8, 1.05}, {2.5, 0.8, 1.05}};
    model_.wires.push_back(wire);
  }

  // A straight cane from `base` along `direction` (normalised here), diameter `diameter_m` at the
  // base tapering to half. Returns its id.
  CaneId Add(const Eigen::Vector3d& base, const Eigen::Vector3d& direction, double length_m,
             double diameter_m, CaneId parent = CaneId(1)) {
    Cane cane;
    cane.id = CaneId(static_cast<int64_t>(model_.canes.size()) + 1);
    cane.parent_id = parent;
    cane.kind = CaneKind::kCane;
    const int n = 10;
    for (int i = 0; i <= n; ++i) {
      const double t = static_cast<double>(i) / n;
      cane.polyline.points.push_back(base + t * length_m * direction.normalized());
      cane.polyline.radii.push_back(0.5 * diameter_m * (1.0 - 0.5 * t * t));
    }
    model_.canes.push_back(cane);
    return cane.id;
  }

  // A cane from the head surface on `side`, heading outward and up at `angle_rad` from horizontal.
  CaneId AddHeadCane(int side, double angle_rad, double length_m, double diameter_m,
                     double base_dx = 0.0) {
    const Eigen::Vector3d base(side * (0.05 + base_dx), 0.8, 1.0);
    return Add(base, Eigen::Vector3d(side * std::cos(angle_rad), 0, std::sin(angle_rad)), length_m,
               diameter_m);
  }

  VineModel& model() { return model_; }

 private:
  VineModel model_;
};

ExpertDecision MustPrune(const VineModel& model, const PruningPolicy& policy = {}) {
  absl::StatusOr<ExpertDecision> d = ExpertPrune(model, policy);
  EXPECT_TRUE(d.ok()) << d.status();
  return d.ok() ? *d : ExpertDecision{};
}

TEST(ExpertPruner, KeepsOneGoodCanePerSideAndSpursNearTheHead) {
  VineBuilder v;
  const CaneId left = v.AddHeadCane(-1, 0.3, 1.0, 0.009);
  const CaneId right = v.AddHeadCane(+1, 0.3, 1.0, 0.009);
  const CaneId right_worse = v.AddHeadCane(+1, 0.3, 1.0, 0.009, 0.03);  // farther from the head
  const CaneId spur_a = v.AddHeadCane(-1, 1.2, 0.4, 0.008, 0.01);
  const CaneId spur_b = v.AddHeadCane(+1, 1.2, 0.4, 0.008, 0.02);
  const CaneId far = v.AddHeadCane(+1, 1.2, 0.4, 0.008, 0.04);
  const ExpertDecision d = MustPrune(v.model());
  EXPECT_THAT(d.keep, ElementsAre(left, right));
  EXPECT_THAT(d.spurs, ElementsAre(spur_a, spur_b));
  EXPECT_THAT(d.notes, IsEmpty());
  (void)right_worse;
  (void)far;
}

TEST(ExpertPruner, PrefersHeadCanesToWaterShootsAndSecondaryCanes) {
  VineBuilder v;
  const CaneId water_shoot = v.Add({-0.02, 0.8, 0.6}, {-1, 0, 0.2}, 1.2, 0.009);
  const CaneId head_left = v.AddHeadCane(-1, 0.3, 0.5, 0.005);  // short and thin, but from the head
  const CaneId right = v.AddHeadCane(+1, 0.3, 1.0, 0.009);
  const CaneId secondary = v.Add({0.3, 0.8, 1.1}, {1, 0, 0.1}, 1.0, 0.009, right);
  const ExpertDecision d = MustPrune(v.model());
  EXPECT_THAT(d.keep, ElementsAre(head_left, right));
  // The secondary cane descends from a kept cane (rule K4): the water shoot is the only spur.
  EXPECT_THAT(d.spurs, ElementsAre(water_shoot));
  ASSERT_EQ(d.notes.size(), 1u);
  EXPECT_THAT(d.notes[0], HasSubstr("only 1 spurs"));
  (void)secondary;
}

TEST(ExpertPruner, RanksDiameterBeforeReachBeforePlacement) {
  VineBuilder v;
  // Left: in range but short, vs too thick and long: diameter wins.
  const CaneId left_in_range = v.AddHeadCane(-1, 0.3, 0.5, 0.009);
  v.AddHeadCane(-1, 0.3, 1.2, 0.014);
  // Right: long but steep beats shorter and flat: reach wins.
  const CaneId right_long = v.AddHeadCane(+1, 1.4, 1.0, 0.009);
  v.AddHeadCane(+1, 0.2, 0.7, 0.009);
  const ExpertDecision d = MustPrune(v.model());
  EXPECT_THAT(d.keep, ElementsAre(left_in_range, right_long));
}

TEST(ExpertPruner, PlacementWeighsBendAgainstDistanceFromTheHead) {
  VineBuilder v;
  v.AddHeadCane(-1, 1.3, 1.0, 0.009);                            // steep, at the head: 1.8
  const CaneId flat = v.AddHeadCane(-1, 0.2, 1.0, 0.009, 0.015);  // flat, 1.5 cm out: 0.85
  v.AddHeadCane(+1, 0.2, 1.0, 0.009, 0.07);                       // flat, far out: 1.4
  const CaneId near = v.AddHeadCane(+1, 0.5, 1.0, 0.009);         // 0.5 rad, at the head: 1.0
  const ExpertDecision d = MustPrune(v.model());
  EXPECT_THAT(d.keep, ElementsAre(flat, near));
}

TEST(ExpertPruner, PrefersBasesBelowTheWire) {
  VineBuilder v;
  const CaneId low = v.AddHeadCane(-1, 0.8, 1.0, 0.009);  // 0.02 m above a 0.98 m wire
  v.Add({-0.01, 0.8, 1.05}, {-1, 0, 0.05}, 1.0, 0.009);   // on top of the head, flat: 0.07 above
  v.AddHeadCane(+1, 0.3, 1.0, 0.009);
  PruningPolicy policy;
  policy.fruiting_wire_z_m = 0.98;
  const ExpertDecision d = MustPrune(v.model(), policy);
  ASSERT_EQ(d.keep.size(), 2u);
  EXPECT_EQ(d.keep[0], low);
}

TEST(ExpertPruner, KeepsBothOnOneSideWhenTheOtherHasNoCane) {
  VineBuilder v;
  const CaneId a = v.AddHeadCane(+1, 0.3, 1.0, 0.009);
  const CaneId b = v.AddHeadCane(+1, 0.5, 1.0, 0.009, 0.03);
  v.AddHeadCane(-1, 0.3, 0.2, 0.009);  // too short to keep
  const ExpertDecision d = MustPrune(v.model());
  EXPECT_THAT(d.keep, ElementsAre(a, b));
  ASSERT_FALSE(d.notes.empty());
  EXPECT_THAT(d.notes[0], HasSubstr("left side"));
}

TEST(ExpertPruner, SpurStyleKeepsNoCanes) {
  VineBuilder v;
  v.AddHeadCane(-1, 0.3, 1.0, 0.009);
  v.AddHeadCane(+1, 0.3, 1.0, 0.009);
  v.AddHeadCane(+1, 0.6, 0.6, 0.008, 0.02);
  PruningPolicy policy;
  policy.style = PruningStyle::kSpur;
  policy.canes_to_keep = 0;
  policy.spurs = 2;
  const ExpertDecision d = MustPrune(v.model(), policy);
  EXPECT_THAT(d.keep, IsEmpty());
  EXPECT_EQ(d.spurs.size(), 2u);
}

TEST(ExpertPruner, MeasuresWhatTheRulesUse) {
  VineBuilder v;
  const CaneId id = v.AddHeadCane(+1, 0.0, 1.0, 0.014);
  v.Add({0.0, 0.8, 0.5}, {1, 0, 0}, 0.5, 0.006);  // a water shoot, well below the head
  absl::StatusOr<std::vector<ExpertCaneView>> views = AssessCanes(v.model(), {});
  ASSERT_TRUE(views.ok()) << views.status();
  ASSERT_EQ(views->size(), 2u);
  const ExpertCaneView& c = (*views)[0];
  EXPECT_EQ(c.id, id);
  EXPECT_EQ(c.origin, ExpertOrigin::kHead);
  EXPECT_EQ(c.side, 1);
  EXPECT_NEAR(c.base_distance_from_head_m, 0.05, 1e-9);
  EXPECT_NEAR(c.base_below_wire_m, 0.05, 1e-9);
  EXPECT_NEAR(c.angle_from_wire_rad, 0.0, 1e-6);
  EXPECT_GT(c.base_diameter_m, 0.0135);  // tapers a little over the first 0.10 m
  EXPECT_NEAR(c.diameter_outside_mm, 1e3 * (c.base_diameter_m - 0.012), 1e-9);
  EXPECT_NEAR(c.placement_rad, 10.0 * 0.05, 1e-6);
  const ExpertCaneView& w = (*views)[1];
  EXPECT_EQ(w.origin, ExpertOrigin::kTrunk);
  EXPECT_NEAR(w.base_below_wire_m, 0.55, 1e-9);
}

TEST(ExpertPruner, RejectsInvalidPolicyAndModel) {
  VineBuilder v;
  v.AddHeadCane(+1, 0.3, 1.0, 0.009);
  PruningPolicy policy;
  policy.canes_to_keep = 9;
  absl::StatusOr<ExpertDecision> bad_policy = ExpertPrune(v.model(), policy);
  ASSERT_FALSE(bad_policy.ok());
  EXPECT_THAT(bad_policy.status().message(), HasSubstr("canes_to_keep"));

  VineModel no_trunk = v.model();
  no_trunk.canes.erase(no_trunk.canes.begin());
  EXPECT_FALSE(ExpertPrune(no_trunk, {}).ok());

  VineModel nan_model = v.model();
  nan_model.canes[1].polyline.points[3].x() = std::nan("");
  EXPECT_EQ(ExpertPrune(nan_model, {}).status().code(), absl::StatusCode::kInvalidArgument);

  VineModel no_canes_at_all = v.model();
  no_canes_at_all.canes.resize(1);
  const ExpertDecision empty = MustPrune(no_canes_at_all);
  EXPECT_THAT(empty.keep, IsEmpty());
  EXPECT_THAT(empty.spurs, IsEmpty());
  EXPECT_EQ(empty.notes.size(), 2u);
}

// On simulated ground truth: deterministic, counts as the policy asks, only canes of kind cane,
// kept canes long enough, no kept cane or spur descending from another, one kept cane per side
// whenever both sides have one.
TEST(ExpertPruner, DecisionsOnSimulatedVinesFollowThePolicy) {
  const PruningPolicy policy;
  int balanced = 0;
  for (int vine = 0; vine < 30; ++vine) {
    absl::StatusOr<Scene> scene = GenerateScene(1100 + vine, vine % 5);
    ASSERT_TRUE(scene.ok()) << scene.status();
    const ExpertDecision d = MustPrune(scene->vine, policy);
    const ExpertDecision again = MustPrune(scene->vine, policy);
    EXPECT_EQ(d.keep, again.keep);
    EXPECT_EQ(d.spurs, again.spurs);
    absl::StatusOr<std::vector<ExpertCaneView>> views = AssessCanes(scene->vine, policy);
    ASSERT_TRUE(views.ok());
    int long_enough = 0;
    int sides[2] = {0, 0};
    for (const ExpertCaneView& c : *views) {
      if (c.length_m >= policy.min_kept_length_m) {
        ++long_enough;
        sides[c.side < 0 ? 0 : 1] = 1;
      }
    }
    EXPECT_EQ(static_cast<int>(d.keep.size()), std::min(policy.canes_to_keep, long_enough));
    EXPECT_EQ(static_cast<int>(d.spurs.size()), policy.spurs);
    std::set<CaneId> chosen(d.keep.begin(), d.keep.end());
    chosen.insert(d.spurs.begin(), d.spurs.end());
    EXPECT_EQ(chosen.size(), d.keep.size() + d.spurs.size());
    int kept_sides[2] = {0, 0};
    for (const ExpertCaneView& c : *views) {
      if (!chosen.contains(c.id)) continue;
      for (CaneId a : c.ancestors) EXPECT_FALSE(chosen.contains(a)) << "vine " << vine;
      if (std::find(d.keep.begin(), d.keep.end(), c.id) != d.keep.end()) {
        EXPECT_GE(c.length_m, policy.min_kept_length_m);
        ++kept_sides[c.side < 0 ? 0 : 1];
      }
    }
    if (sides[0] && sides[1]) {
      EXPECT_EQ(kept_sides[0], 1) << "vine " << vine;
      EXPECT_EQ(kept_sides[1], 1) << "vine " << vine;
      ++balanced;
    }
  }
  EXPECT_GT(balanced, 20);  // the check above must have bitten
}

}  // namespace
}  // namespace vb::sim
