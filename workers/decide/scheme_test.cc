// SPDX-License-Identifier: Apache-2.0
#include "workers/decide/scheme.h"

#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace vb::decide {
namespace {

using nlohmann::json;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

Cane MakeCane(int id, std::optional<int> parent, CaneKind kind,
              std::vector<Eigen::Vector3d> points, double radius) {
  Cane cane;
  cane.id = CaneId(id);
  if (parent) cane.parent_id = CaneId(*parent);
  cane.kind = kind;
  cane.polyline.points = std::move(points);
  cane.polyline.radii.assign(cane.polyline.points.size(), radius);
  return cane;
}

// Trunk up to a head at (0, 0.8, 0.9); a fruiting wire at 1.0 (sagging to 0.98 at x = 0).
VineModel TestVine() {
  VineModel m;
  m.canes.push_back(MakeCane(1, std::nullopt, CaneKind::kTrunk, {{0, 0.8, 0}, {0, 0.8, 0.9}}, 0.02));
  // 2: from the head going right along the row, 1 m long.
  m.canes.push_back(MakeCane(2, 1, CaneKind::kCane, {{0.04, 0.8, 0.9}, {1.04, 0.8, 0.9}}, 0.005));
  // 3: from the head going left and up at 45 degrees.
  m.canes.push_back(
      MakeCane(3, 1, CaneKind::kCane, {{-0.04, 0.8, 0.92}, {-0.44, 0.8, 1.32}}, 0.004));
  // 4: a water shoot from the trunk at 0.5 m, going straight up.
  m.canes.push_back(MakeCane(4, 1, CaneKind::kCane, {{0.02, 0.8, 0.5}, {0.02, 0.8, 0.8}}, 0.003));
  // 5: a secondary cane from cane 2, 0.3 m along it.
  m.canes.push_back(MakeCane(5, 2, CaneKind::kCane, {{0.34, 0.8, 0.9}, {0.34, 0.8, 1.3}}, 0.003));
  // 6: an old spur; 7: a cane growing from it.
  m.canes.push_back(MakeCane(6, 1, CaneKind::kSpur, {{0, 0.8, 0.93}, {0, 0.8, 1.0}}, 0.008));
  m.canes.push_back(MakeCane(7, 6, CaneKind::kCane, {{0, 0.8, 1.0}, {0, 0.8, 1.5}}, 0.004));
  // 8: a tertiary cane from 5.
  m.canes.push_back(MakeCane(8, 5, CaneKind::kCane, {{0.34, 0.8, 1.1}, {0.5, 0.8, 1.1}}, 0.002));
  m.head.spheres = {{Eigen::Vector3d(0, 0.8, 0.9), 0.04}};
  m.wires = {{WireId(1), {{-2, 0.8, 1.0}, {0, 0.8, 0.98}, {2, 0.8, 1.0}}, 0.0015},
             {WireId(2), {{-2, 0.8, 1.3}, {2, 0.8, 1.3}}, 0.0015}};
  return m;
}

const Candidate& ById(const std::vector<Candidate>& cands, int id) {
  for (const Candidate& c : cands) {
    if (c.id == CaneId(id)) return c;
  }
  ADD_FAILURE() << "no candidate " << id;
  return cands.front();
}

TEST(FindCandidates, MeasuresEveryCaneOfKindCane) {
  auto cands = FindCandidates(TestVine(), PruningPolicy{});
  ASSERT_TRUE(cands.ok()) << cands.status();
  ASSERT_EQ(cands->size(), 6u);  // not the trunk, not the old spur 6
  EXPECT_EQ((*cands)[0].id, CaneId(2));
  EXPECT_EQ((*cands)[0].cane_index, 1u);

  const Candidate& c2 = ById(*cands, 2);
  EXPECT_EQ(c2.origin, CaneOrigin::kHead);
  EXPECT_NEAR(c2.length_m, 1.0, 1e-12);
  EXPECT_NEAR(c2.base_diameter_m, 0.010, 1e-12);
  EXPECT_NEAR(c2.base_distance_from_head_m, 0.04, 1e-12);
  EXPECT_NEAR(c2.angle_from_head_rad, 0.0, 1e-9);
  EXPECT_EQ(c2.side, 1);
  EXPECT_NEAR(c2.wire_z_m, 0.98, 1e-12);  // lowest wire at the head's x
  EXPECT_TRUE(c2.ancestors.empty());

  const Candidate& c3 = ById(*cands, 3);
  EXPECT_EQ(c3.side, -1);
  EXPECT_NEAR(c3.angle_from_head_rad, std::numbers::pi / 4, 1e-9);
  EXPECT_EQ(c3.origin, CaneOrigin::kHead);

  const Candidate& c4 = ById(*cands, 4);
  EXPECT_EQ(c4.origin, CaneOrigin::kTrunk);
  EXPECT_NEAR(c4.angle_from_head_rad, std::numbers::pi / 2, 1e-9);

  EXPECT_EQ(ById(*cands, 5).origin, CaneOrigin::kCane);
  EXPECT_THAT(ById(*cands, 5).ancestors, ElementsAre(CaneId(2)));
  EXPECT_THAT(ById(*cands, 8).ancestors, ElementsAre(CaneId(5), CaneId(2)));
  // From an old spur on the head: a head cane; the spur is no candidate ancestor.
  EXPECT_EQ(ById(*cands, 7).origin, CaneOrigin::kHead);
  EXPECT_TRUE(ById(*cands, 7).ancestors.empty());
}

TEST(FindCandidates, BaseDiameterIsTheMeanOverTheFirstTenCentimetres) {
  VineModel m = TestVine();
  // Radius 6 mm at the base tapering linearly to 4 mm at 0.2 m: mean over 0.1 m is 5.5 mm.
  m.canes[1].polyline.points = {{0.04, 0.8, 0.9}, {0.24, 0.8, 0.9}, {1.04, 0.8, 0.9}};
  m.canes[1].polyline.radii = {0.006, 0.004, 0.002};
  auto cands = FindCandidates(m, PruningPolicy{});
  ASSERT_TRUE(cands.ok());
  EXPECT_NEAR(ById(*cands, 2).base_diameter_m, 0.0110, 1e-12);
}

TEST(FindCandidates, WireHeightFromPolicyModelOrDefault) {
  PruningPolicy policy;
  policy.fruiting_wire_z_m = 1.05;
  auto from_policy = FindCandidates(TestVine(), policy);
  ASSERT_TRUE(from_policy.ok());
  EXPECT_DOUBLE_EQ((*from_policy)[0].wire_z_m, 1.05);
  VineModel no_wires = TestVine();
  no_wires.wires.clear();
  auto fallback = FindCandidates(no_wires, PruningPolicy{});
  ASSERT_TRUE(fallback.ok());
  EXPECT_DOUBLE_EQ((*fallback)[0].wire_z_m, 0.95);
}

TEST(FindCandidates, WithoutHeadSpheresTheTrunkTopIsTheHead) {
  VineModel m = TestVine();
  m.head.spheres.clear();
  auto cands = FindCandidates(m, PruningPolicy{});
  ASSERT_TRUE(cands.ok());
  EXPECT_NEAR(ById(*cands, 2).base_distance_from_head_m, 0.04, 1e-12);
  EXPECT_EQ(ById(*cands, 2).origin, CaneOrigin::kHead);
  EXPECT_EQ(ById(*cands, 4).origin, CaneOrigin::kTrunk);
}

TEST(FindCandidates, RejectsInvalidModelsAndPolicies) {
  VineModel m = TestVine();
  m.canes[0].kind = CaneKind::kCane;
  m.canes[0].parent_id = CaneId(2);  // no trunk, and a cycle 1 -> 2 -> 1
  EXPECT_THAT(FindCandidates(m, PruningPolicy{}).status().message(), HasSubstr("cycle"));
  VineModel no_trunk;
  EXPECT_THAT(FindCandidates(no_trunk, PruningPolicy{}).status().message(),
              HasSubstr("model: no trunk"));
  PruningPolicy bad;
  bad.cut_offset_m = -1;
  EXPECT_THAT(FindCandidates(TestVine(), bad).status().message(), HasSubstr("policy.cut_offset_m"));
}

TEST(SchemeFeatures, SumsPerCaneFeaturesAndImbalance) {
  auto cands = FindCandidates(TestVine(), PruningPolicy{});
  ASSERT_TRUE(cands.ok());
  PruningPolicy policy;  // max kept length 0.9, preferred diameter 7-12 mm
  const FeatureVector k2 = KeepFeatures(ById(*cands, 2), policy);
  EXPECT_DOUBLE_EQ(k2[kKeepLengthShortfallM], 0.0);
  EXPECT_DOUBLE_EQ(k2[kKeepDiameterOutsideMm], 0.0);
  EXPECT_NEAR(k2[kKeepBelowWireM], 0.08, 1e-12);
  EXPECT_DOUBLE_EQ(k2[kKeepAboveWireM], 0.0);
  EXPECT_DOUBLE_EQ(k2[kSpurBaseDistanceM], 0.0);  // keep features only
  const FeatureVector k4 = KeepFeatures(ById(*cands, 4), policy);
  EXPECT_NEAR(k4[kKeepLengthShortfallM], 0.6, 1e-12);
  EXPECT_NEAR(k4[kKeepDiameterOutsideMm], 1.0, 1e-9);  // 6 mm vs 7 mm
  EXPECT_DOUBLE_EQ(k4[kKeepFromTrunk], 1.0);
  const FeatureVector s5 = SpurFeatures(ById(*cands, 5), policy);
  EXPECT_DOUBLE_EQ(s5[kSpurFromCane], 1.0);
  EXPECT_NEAR(s5[kSpurDiameterOutsideMm], 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(s5[kKeepFromCane], 0.0);

  const Scheme scheme{{CaneId(2), CaneId(4)}, {CaneId(5)}};
  const FeatureVector f = SchemeFeatures(*cands, policy, scheme);
  const FeatureVector expected = k2 + k4 + s5;
  for (int i = 0; i < kImbalance; ++i) EXPECT_DOUBLE_EQ(f[i], expected[i]) << SchemeFeatureName(i);
  EXPECT_DOUBLE_EQ(f[kImbalance], 2.0);  // both right of the head centre
  const Scheme balanced{{CaneId(2), CaneId(3)}, {}};
  EXPECT_DOUBLE_EQ(SchemeFeatures(*cands, policy, balanced)[kImbalance], 0.0);
}

TEST(SchemeWeights, DefaultsAreValidAndPreferAGoodHeadCane) {
  const SchemeWeights w = DefaultSchemeWeights();
  EXPECT_TRUE(w.Validate().ok());
  auto cands = FindCandidates(TestVine(), PruningPolicy{});
  ASSERT_TRUE(cands.ok());
  const PruningPolicy policy;
  const double head_cane = w.w.dot(KeepFeatures(ById(*cands, 2), policy));
  for (int other : {3, 4, 5, 7, 8}) {
    EXPECT_LT(head_cane, w.w.dot(KeepFeatures(ById(*cands, other), policy))) << other;
  }
  for (int f = 0; f < kSchemeFeatureCount; ++f) EXPECT_GT(w.w[f], 0.0) << SchemeFeatureName(f);
}

TEST(SchemeWeights, JsonRoundTripsAndNamesEveryFeature) {
  SchemeWeights w = DefaultSchemeWeights();
  w.w[kImbalance] = -0.25;
  const json j = SchemeWeightsToJson(w);
  EXPECT_EQ(j["version"], 1);
  EXPECT_EQ(j["weights"].size(), static_cast<size_t>(kSchemeFeatureCount));
  EXPECT_EQ(j["weights"]["imbalance"], -0.25);
  EXPECT_EQ(j["weights"]["keep_length_shortfall_m"], w.w[kKeepLengthShortfallM]);
  auto back = SchemeWeightsFromJson(json::parse(j.dump()));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->w, w.w);
  EXPECT_EQ(SchemeFeatureName(kSpurDiameterOutsideMm), "spur_diameter_outside_mm");
  EXPECT_EQ(SchemeFeatureName(kSchemeFeatureCount), "unknown");
}

TEST(SchemeWeights, FromJsonRejectsIncompleteUnknownAndBadValues) {
  const json good = SchemeWeightsToJson(DefaultSchemeWeights());
  struct Case {
    std::function<void(json&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](json& j) { j["weights"].erase("keep_angle_rad"); }, "weights.keep_angle_rad: missing"},
      {[](json& j) { j["weights"]["keep_colour"] = 1; }, "weights.keep_colour: unknown feature"},
      {[](json& j) { j["weights"]["imbalance"] = "1"; }, "weights.imbalance: not a number"},
      {[](json& j) { j["version"] = 2; }, "weights.version: 2"},
      {[](json& j) { j.erase("version"); }, "version: missing"},
      {[](json& j) { j["weights"] = json::array(); }, "weights: not an object"},
      {[](json& j) { j["bias"] = 0; }, "bias: unknown field"},
  };
  for (const Case& c : cases) {
    json j = good;
    c.edit(j);
    auto w = SchemeWeightsFromJson(j);
    EXPECT_EQ(w.status().code(), absl::StatusCode::kInvalidArgument) << c.message;
    EXPECT_THAT(w.status().message(), HasSubstr(c.message));
  }
}

}  // namespace
}  // namespace vb::decide
