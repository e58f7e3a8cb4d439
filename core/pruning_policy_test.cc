// SPDX-License-Identifier: Apache-2.0
#include "core/pruning_policy.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/json_io.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace vb {
namespace {

using nlohmann::json;
using ::testing::HasSubstr;

TEST(PruningPolicy, DefaultsAreValid) {
  const PruningPolicy policy;
  EXPECT_TRUE(policy.Validate().ok()) << policy.Validate();
  EXPECT_EQ(policy.style, PruningStyle::kCane);
  EXPECT_EQ(policy.canes_to_keep, 2);
  EXPECT_EQ(policy.spurs, 2);
  EXPECT_DOUBLE_EQ(policy.cut_offset_m, 0.01);
}

TEST(PruningPolicy, ValidateNamesTheBadField) {
  struct Case {
    std::function<void(PruningPolicy&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](PruningPolicy& p) { p.version = 2; }, "policy.version: 2"},
      {[](PruningPolicy& p) { p.canes_to_keep = 9; }, "policy.canes_to_keep: 9 is outside [1, 6]"},
      {[](PruningPolicy& p) { p.canes_to_keep = 0; }, "policy.canes_to_keep: 0"},
      {[](PruningPolicy& p) { p.spurs = 7; }, "policy.spurs: 7"},
      {[](PruningPolicy& p) { p.spurs = -1; }, "policy.spurs: -1"},
      {[](PruningPolicy& p) { p.spur_length_m = 0.0; }, "policy.spur_length_m"},
      {[](PruningPolicy& p) { p.spur_length_m = std::nan(""); }, "policy.spur_length_m: not finite"},
      {[](PruningPolicy& p) { p.cane_diameter_min_m = 7.0; }, "policy.cane_diameter_min_m"},
      {[](PruningPolicy& p) { p.cane_diameter_min_m = 0.013; },
       "policy.cane_diameter_min_m: 0.013 is greater than policy.cane_diameter_max_m"},
      {[](PruningPolicy& p) { p.cane_diameter_max_m = -0.01; }, "policy.cane_diameter_max_m"},
      {[](PruningPolicy& p) { p.min_kept_length_m = 1.0; },
       "policy.min_kept_length_m: 1 is greater than policy.max_kept_length_m"},
      {[](PruningPolicy& p) { p.max_kept_length_m = std::numeric_limits<double>::infinity(); },
       "policy.max_kept_length_m: not finite"},
      {[](PruningPolicy& p) { p.cut_offset_m = 0.0; }, "policy.cut_offset_m"},
      {[](PruningPolicy& p) { p.fruiting_wire_z_m = -1.0; }, "policy.fruiting_wire_z_m"},
      {[](PruningPolicy& p) {
         p.fruiting_wire_z_m = 1.0;
         p.foliage_wire_z_m = {1.3, 0.9};
       },
       "policy.foliage_wire_z_m[1]: 0.9 is not above policy.fruiting_wire_z_m"},
  };
  for (const Case& c : cases) {
    PruningPolicy policy;
    c.edit(policy);
    const absl::Status status = policy.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << c.message;
    EXPECT_THAT(status.message(), HasSubstr(c.message));
  }
}

TEST(PruningPolicy, SpurStyleKeepsNoCanes) {
  PruningPolicy policy;
  policy.style = PruningStyle::kSpur;
  policy.canes_to_keep = 0;
  policy.spurs = 12;
  EXPECT_TRUE(policy.Validate().ok());
  policy.canes_to_keep = 1;
  EXPECT_THAT(policy.Validate().message(), HasSubstr("policy.canes_to_keep: 1"));
  policy.canes_to_keep = 0;
  policy.spurs = 0;
  EXPECT_THAT(policy.Validate().message(), HasSubstr("policy.spurs: 0 is outside [1, 12]"));
}

TEST(PruningPolicy, StyleNamesRoundTrip) {
  for (PruningStyle style : {PruningStyle::kCane, PruningStyle::kSpur}) {
    auto parsed = ParsePruningStyle(PruningStyleName(style));
    ASSERT_TRUE(parsed.ok());
    EXPECT_EQ(*parsed, style);
  }
  EXPECT_THAT(ParsePruningStyle("guyot").status().message(), HasSubstr("policy.style"));
}

TEST(PruningPolicyJson, RoundTripsEveryField) {
  PruningPolicy policy;
  policy.canes_to_keep = 4;
  policy.spurs = 3;
  policy.spur_length_m = 0.12;
  policy.cane_diameter_min_m = 0.006;
  policy.cane_diameter_max_m = 0.011;
  policy.min_kept_length_m = 0.4;
  policy.max_kept_length_m = 1.1;
  policy.cut_offset_m = 0.015;
  policy.fruiting_wire_z_m = 0.92;
  policy.foliage_wire_z_m = {1.2, 1.5};
  const json j = PruningPolicyToJson(policy);
  EXPECT_EQ(j["style"], "cane");
  EXPECT_EQ(j["version"], 1);
  auto back = PruningPolicyFromJson(json::parse(j.dump()));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(PruningPolicyToJson(*back), j);
  EXPECT_EQ(back->fruiting_wire_z_m, 0.92);
  EXPECT_EQ(back->foliage_wire_z_m, (std::vector<double>{1.2, 1.5}));
}

TEST(PruningPolicyJson, UnsetWireIsNull) {
  const json j = PruningPolicyToJson(PruningPolicy{});
  EXPECT_TRUE(j["fruiting_wire_z_m"].is_null());
  auto back = PruningPolicyFromJson(j);
  ASSERT_TRUE(back.ok());
  EXPECT_FALSE(back->fruiting_wire_z_m.has_value());
}

TEST(PruningPolicyJson, PartialFileKeepsDefaults) {
  auto policy = PruningPolicyFromJson(json::parse(R"({"canes_to_keep": 4})"));
  ASSERT_TRUE(policy.ok()) << policy.status();
  EXPECT_EQ(policy->canes_to_keep, 4);
  EXPECT_EQ(policy->spurs, 2);
  EXPECT_DOUBLE_EQ(policy->spur_length_m, 0.10);
  EXPECT_DOUBLE_EQ(policy->cut_offset_m, 0.01);
  auto empty = PruningPolicyFromJson(json::object());
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(PruningPolicyToJson(*empty), PruningPolicyToJson(PruningPolicy{}));
}

TEST(PruningPolicyJson, SpurStyleFileNeedNotZeroCanesToKeep) {
  auto policy = PruningPolicyFromJson(json::parse(R"({"style": "spur", "spurs": 8})"));
  ASSERT_TRUE(policy.ok()) << policy.status();
  EXPECT_EQ(policy->style, PruningStyle::kSpur);
  EXPECT_EQ(policy->canes_to_keep, 0);
  EXPECT_EQ(policy->spurs, 8);
  // Said explicitly, it must be 0.
  EXPECT_THAT(PruningPolicyFromJson(json::parse(R"({"style": "spur", "canes_to_keep": 2})"))
                  .status()
                  .message(),
              HasSubstr("policy.canes_to_keep"));
}

TEST(PruningPolicyJson, RejectsUnknownFieldsWrongTypesAndBadValues) {
  struct Case {
    const char* text;
    const char* message;
  };
  const Case cases[] = {
      {R"({"canes_to_kep": 3})", "policy.canes_to_kep: unknown field"},
      {R"({"canes_to_keep": 2.5})", "policy.canes_to_keep: not an integer"},
      {R"({"canes_to_keep": "2"})", "policy.canes_to_keep: not an integer"},
      {R"({"spurs": 99999999999})", "policy.spurs"},
      {R"({"spur_length_m": "long"})", "policy.spur_length_m: not a number"},
      {R"({"style": 1})", "policy.style: not a string"},
      {R"({"style": "guyot"})", "policy.style: unknown style 'guyot'"},
      {R"({"fruiting_wire_z_m": "high"})", "policy.fruiting_wire_z_m: not a number"},
      {R"({"foliage_wire_z_m": 1.2})", "policy.foliage_wire_z_m: not an array"},
      {R"({"foliage_wire_z_m": [1.2, null]})", "policy.foliage_wire_z_m[1]: not a number"},
      {R"({"canes_to_keep": 7})", "policy.canes_to_keep: 7 is outside [1, 6]"},
      {R"({"version": 2})", "policy.version"},
      {R"([1, 2])", "policy: not a JSON object"},
  };
  for (const Case& c : cases) {
    auto policy = PruningPolicyFromJson(json::parse(c.text));
    EXPECT_EQ(policy.status().code(), absl::StatusCode::kInvalidArgument) << c.text;
    EXPECT_THAT(policy.status().message(), HasSubstr(c.message)) << c.text;
  }
}

TEST(PruningPolicyJson, ReadPrefixesErrorsWithThePath) {
  const std::string path =
      testing::TempDir() + "/policy_test_" + std::to_string(getpid()) + ".json";
  {
    std::ofstream out(path);
    out << R"({"canes_to_keep": 3, "spur_length_m": 0.08})";
  }
  auto policy = ReadPruningPolicy(path);
  ASSERT_TRUE(policy.ok()) << policy.status();
  EXPECT_EQ(policy->canes_to_keep, 3);
  EXPECT_DOUBLE_EQ(policy->spur_length_m, 0.08);
  {
    std::ofstream out(path);
    out << R"({"spurs": 40})";
  }
  auto bad = ReadPruningPolicy(path);
  EXPECT_THAT(bad.status().message(), HasSubstr(path + ": policy.spurs: 40"));
  std::remove(path.c_str());
  EXPECT_EQ(ReadPruningPolicy(path).status().code(), absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace vb
