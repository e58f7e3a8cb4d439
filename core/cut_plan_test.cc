// SPDX-License-Identifier: Apache-2.0
#include "core/cut_plan.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace vb {
namespace {

using nlohmann::json;
using ::testing::HasSubstr;

CutPlan SamplePlan() {
  CutPlan plan;
  plan.policy.canes_to_keep = 2;
  plan.policy.fruiting_wire_z_m = 0.95;
  plan.keep = {CaneId(2), CaneId(5)};
  plan.spurs = {CaneId(3)};
  Cut remove;
  remove.id = CutId(1);
  remove.cane_id = CaneId(4);
  remove.point = {0.1, 0.8, 0.93};
  remove.direction = Eigen::Vector3d(1, 0, 1).normalized();
  remove.diameter_m = 0.009;
  remove.reason = CutReason::kRemove;
  Cut spur = remove;
  spur.id = CutId(2);
  spur.cane_id = CaneId(3);
  spur.point = {-0.05, 0.8, 1.02};
  spur.direction = {0, 0, 1};
  spur.diameter_m = 0.0075;
  spur.reason = CutReason::kSpur;
  plan.cuts = {remove, spur};
  return plan;
}

VineModel ModelWithCanes(std::initializer_list<int> ids) {
  VineModel model;
  for (int id : ids) {
    Cane cane;
    cane.id = CaneId(id);
    cane.kind = id == 1 ? CaneKind::kTrunk : CaneKind::kCane;
    if (id != 1) cane.parent_id = CaneId(1);
    cane.polyline.points = {{0, 0, 0}, {0, 0, 1}};
    cane.polyline.radii = {0.01, 0.01};
    model.canes.push_back(cane);
  }
  return model;
}

TEST(CutPlan, ReasonNamesRoundTrip) {
  for (CutReason r : {CutReason::kRemove, CutReason::kSpur, CutReason::kShorten}) {
    auto parsed = ParseCutReason(CutReasonName(r));
    ASSERT_TRUE(parsed.ok());
    EXPECT_EQ(*parsed, r);
  }
  EXPECT_EQ(CutReasonName(CutReason::kShorten), "shorten");
  EXPECT_THAT(ParseCutReason("trim").status().message(), HasSubstr("'trim'"));
}

TEST(CutPlan, JsonHasTheArchitectureLayout) {
  const json j = CutPlanToJson(SamplePlan());
  EXPECT_EQ(j["format"], "vinebot.cut_plan.v1");
  EXPECT_EQ(j["keep"], json::parse("[2, 5]"));
  EXPECT_EQ(j["spurs"], json::parse("[3]"));
  EXPECT_EQ(j["policy"]["canes_to_keep"], 2);
  EXPECT_EQ(j["policy"]["fruiting_wire_z_m"], 0.95);
  ASSERT_EQ(j["cuts"].size(), 2u);
  const json& cut = j["cuts"][0];
  EXPECT_EQ(cut["id"], 1);
  EXPECT_EQ(cut["cane_id"], 4);
  EXPECT_EQ(cut["point"], json::parse("[0.1, 0.8, 0.93]"));
  EXPECT_EQ(cut["diameter_m"], 0.009);
  EXPECT_EQ(cut["reason"], "remove");
  EXPECT_EQ(j["cuts"][1]["reason"], "spur");
  EXPECT_EQ(cut.size(), 6u);
  EXPECT_EQ(j.size(), 5u);
}

TEST(CutPlan, RoundTripsExactly) {
  const CutPlan plan = SamplePlan();
  auto back = CutPlanFromJson(json::parse(CutPlanToJson(plan).dump()));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->keep, plan.keep);
  EXPECT_EQ(back->spurs, plan.spurs);
  ASSERT_EQ(back->cuts.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back->cuts[i].id, plan.cuts[i].id);
    EXPECT_EQ(back->cuts[i].cane_id, plan.cuts[i].cane_id);
    EXPECT_EQ(back->cuts[i].point, plan.cuts[i].point);
    EXPECT_EQ(back->cuts[i].direction, plan.cuts[i].direction);
    EXPECT_EQ(back->cuts[i].diameter_m, plan.cuts[i].diameter_m);
    EXPECT_EQ(back->cuts[i].reason, plan.cuts[i].reason);
  }
  EXPECT_EQ(PruningPolicyToJson(back->policy), PruningPolicyToJson(plan.policy));
}

TEST(CutPlan, FileRoundTripAndPathInErrors) {
  const std::string path = testing::TempDir() + "/cut_plan_test_" +
                           std::to_string(getpid()) + ".json";
  ASSERT_TRUE(WriteCutPlan(path, SamplePlan()).ok());
  auto back = ReadCutPlan(path);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->cuts.size(), 2u);
  {
    std::ofstream out(path);
    out << R"({"format": "vinebot.cut_plan.v2"})";
  }
  EXPECT_THAT(ReadCutPlan(path).status().message(), HasSubstr(path + ": format"));
  std::remove(path.c_str());
  EXPECT_EQ(ReadCutPlan(path).status().code(), absl::StatusCode::kNotFound);
}

TEST(CutPlan, ValidateNamesTheBadElement) {
  struct Case {
    std::function<void(CutPlan&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](CutPlan& p) { p.policy.spurs = 20; }, "policy.spurs: 20"},
      {[](CutPlan& p) { p.cuts[1].id = CutId(1); }, "cuts[1] (id 1).id: duplicate cut id"},
      {[](CutPlan& p) { p.cuts[0].id = CutId(0); }, "cuts[0] (id 0).id: must be positive"},
      {[](CutPlan& p) { p.spurs.push_back(CaneId(5)); }, "spurs[1]: cane 5 is also kept"},
      {[](CutPlan& p) { p.keep.push_back(CaneId(2)); }, "keep[2]: cane 2 is listed twice"},
      {[](CutPlan& p) { p.cuts[1].point.x() = std::nan(""); }, "cuts[1] (id 2).point: not finite"},
      {[](CutPlan& p) { p.cuts[0].direction = {0, 0, 2}; },
       "cuts[0] (id 1).direction: not a unit vector (norm 2)"},
      {[](CutPlan& p) { p.cuts[0].diameter_m = 0.0; }, "cuts[0] (id 1).diameter_m"},
      {[](CutPlan& p) { p.cuts[1].diameter_m = INFINITY; }, "cuts[1] (id 2).diameter_m"},
  };
  for (const Case& c : cases) {
    CutPlan plan = SamplePlan();
    ASSERT_TRUE(plan.Validate().ok());
    c.edit(plan);
    const absl::Status status = plan.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << c.message;
    EXPECT_THAT(status.message(), HasSubstr(c.message));
  }
}

TEST(CutPlan, ValidateAgainstChecksEveryCaneExists) {
  const CutPlan plan = SamplePlan();
  EXPECT_TRUE(plan.ValidateAgainst(ModelWithCanes({1, 2, 3, 4, 5})).ok());
  EXPECT_THAT(plan.ValidateAgainst(ModelWithCanes({1, 3, 4, 5})).message(),
              HasSubstr("keep[0]: cane 2 is not in the model"));
  EXPECT_THAT(plan.ValidateAgainst(ModelWithCanes({1, 2, 4, 5})).message(),
              HasSubstr("spurs[0]: cane 3 is not in the model"));
  EXPECT_THAT(plan.ValidateAgainst(ModelWithCanes({1, 2, 3, 5})).message(),
              HasSubstr("cuts[0] (id 1).cane_id: cane 4 is not in the model"));
  CutPlan bad = plan;
  bad.cuts[0].diameter_m = -1;
  EXPECT_THAT(bad.ValidateAgainst(ModelWithCanes({1, 2, 3, 4, 5})).message(),
              HasSubstr("diameter_m"));
}

TEST(CutPlan, FromJsonRejectsMalformedInputNamingTheField) {
  const json good = CutPlanToJson(SamplePlan());
  struct Case {
    std::function<void(json&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](json& j) { j.erase("keep"); }, "keep: missing"},
      {[](json& j) { j["keep"] = 2; }, "keep: not an array"},
      {[](json& j) { j["spurs"][0] = "3"; }, "spurs[0]: not an integer"},
      {[](json& j) { j.erase("policy"); }, "policy: missing"},
      {[](json& j) { j["policy"]["cut_offset"] = 0.01; }, "policy.cut_offset: unknown field"},
      {[](json& j) { j["notes"] = "x"; }, "notes: unknown field"},
      {[](json& j) { j["cuts"] = json::object(); }, "cuts: not an array"},
      {[](json& j) { j["cuts"][0].erase("point"); }, "cuts[0].point: missing"},
      {[](json& j) { j["cuts"][0]["point"] = {1, 2}; }, "cuts[0].point: expected [x, y, z]"},
      {[](json& j) { j["cuts"][1]["direction"][2] = "up"; }, "cuts[1].direction[2]: not a number"},
      {[](json& j) { j["cuts"][0]["reason"] = "trim"; }, "cuts[0].reason: unknown cut reason"},
      {[](json& j) { j["cuts"][0]["diameter_m"] = "9mm"; }, "cuts[0].diameter_m: not a number"},
      {[](json& j) { j["cuts"][0]["cane_id"] = 4.5; }, "cuts[0].cane_id: not an integer"},
      {[](json& j) { j["cuts"][0]["colour"] = "red"; }, "cuts[0].colour: unknown field"},
      {[](json& j) { j["cuts"][1]["id"] = 1; }, "cuts[1] (id 1).id: duplicate cut id"},
      {[](json& j) { j["format"] = "vinebot.vine_model.v1"; }, "format: expected"},
  };
  for (const Case& c : cases) {
    json j = good;
    c.edit(j);
    auto plan = CutPlanFromJson(j);
    EXPECT_EQ(plan.status().code(), absl::StatusCode::kInvalidArgument) << c.message;
    EXPECT_THAT(plan.status().message(), HasSubstr(c.message));
  }
}

}  // namespace
}  // namespace vb
