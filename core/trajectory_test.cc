// SPDX-License-Identifier: Apache-2.0
#include "core/trajectory.h"

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

Trajectory SampleTrajectory() {
  Trajectory t;
  t.platform_from_arm_base.translation() << 0.1, 0.3, 0.5;
  t.platform_from_arm_base.linear() =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  t.tool.name = "mill_end";
  t.tool.flange_from_tcp.translation() << 0, 0, 0.2;
  t.tool.flange_from_tcp.linear() =
      Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  t.tool.capsules = {{{0, 0, 0}, {0, 0, 0.15}, 0.04}, {{0, 0, 0.15}, {0, 0, 0.22}, 0.003}};
  TrajectorySegment transit;
  transit.points = {{0.0, {0, -1.5, 1.2, 0, 1.57, 0}}, {0.8, {0.2, -1.4, 1.1, 0.1, 1.5, 0.3}}};
  TrajectorySegment cut;
  cut.kind = SegmentKind::kCut;
  cut.cut_id = CutId(7);
  cut.points = {{0.9, {0.2, -1.4, 1.1, 0.1, 1.5, 0.3}}, {1.3, {0.25, -1.35, 1.05, 0.1, 1.5, 0.3}}};
  t.segments = {transit, cut};
  t.duration_s = 1.3;
  t.unplanned = {{CutId(3), "unreachable"}};
  return t;
}

TEST(Trajectory, JsonHasTheArchitectureLayout) {
  const json j = TrajectoryToJson(SampleTrajectory());
  EXPECT_EQ(j["format"], "vinebot.trajectory.v1");
  EXPECT_EQ(j["robot"], "ur5");
  EXPECT_EQ(j["platform_from_arm_base"]["translation"].size(), 3u);
  EXPECT_EQ(j["platform_from_arm_base"]["rotation_xyzw"].size(), 4u);
  EXPECT_EQ(j["tool"]["name"], "mill_end");
  EXPECT_EQ(j["tool"]["capsules"][1]["radius"], 0.003);
  EXPECT_EQ(j["segments"][0]["kind"], "transit");
  EXPECT_FALSE(j["segments"][0].contains("cut_id"));
  EXPECT_EQ(j["segments"][1]["kind"], "cut");
  EXPECT_EQ(j["segments"][1]["cut_id"], 7);
  EXPECT_EQ(j["segments"][1]["points"][0]["t"], 0.9);
  EXPECT_EQ(j["segments"][1]["points"][0]["q"].size(), 6u);
  EXPECT_EQ(j["duration_s"], 1.3);
  EXPECT_EQ(j["unplanned"][0]["cut_id"], 3);
  EXPECT_EQ(j["unplanned"][0]["reason"], "unreachable");
}

TEST(Trajectory, RoundTripsThroughJson) {
  const Trajectory t = SampleTrajectory();
  ASSERT_TRUE(t.Validate().ok()) << t.Validate();
  // Through text, as a file would carry it.
  auto back = TrajectoryFromJson(json::parse(TrajectoryToJson(t).dump()));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->robot, t.robot);
  EXPECT_TRUE(back->platform_from_arm_base.isApprox(t.platform_from_arm_base, 1e-14));
  EXPECT_TRUE(back->tool.flange_from_tcp.isApprox(t.tool.flange_from_tcp, 1e-14));
  EXPECT_EQ(back->tool.name, "mill_end");
  ASSERT_EQ(back->tool.capsules.size(), 2u);
  EXPECT_EQ(back->tool.capsules[1].b, t.tool.capsules[1].b);
  EXPECT_EQ(back->tool.capsules[1].radius, t.tool.capsules[1].radius);
  ASSERT_EQ(back->segments.size(), 2u);
  for (size_t s = 0; s < 2; ++s) {
    EXPECT_EQ(back->segments[s].kind, t.segments[s].kind);
    EXPECT_EQ(back->segments[s].cut_id, t.segments[s].cut_id);
    ASSERT_EQ(back->segments[s].points.size(), t.segments[s].points.size());
    for (size_t p = 0; p < t.segments[s].points.size(); ++p) {
      EXPECT_EQ(back->segments[s].points[p].t, t.segments[s].points[p].t);
      EXPECT_EQ(back->segments[s].points[p].q, t.segments[s].points[p].q);
    }
  }
  EXPECT_EQ(back->duration_s, 1.3);
  ASSERT_EQ(back->unplanned.size(), 1u);
  EXPECT_EQ(back->unplanned[0].cut_id, CutId(3));
  EXPECT_EQ(back->unplanned[0].reason, "unreachable");
}

TEST(Trajectory, FileRoundTripAndPathInErrors) {
  const std::string path = testing::TempDir() + "/trajectory_test_" +
                           std::to_string(getpid()) + ".json";
  ASSERT_TRUE(WriteTrajectory(path, SampleTrajectory()).ok());
  auto back = ReadTrajectory(path);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->segments.size(), 2u);
  {
    std::ofstream out(path);
    out << R"({"format": "vinebot.trajectory.v0"})";
  }
  EXPECT_THAT(ReadTrajectory(path).status().message(), HasSubstr(path + ": format"));
  std::remove(path.c_str());
  EXPECT_EQ(ReadTrajectory(path).status().code(), absl::StatusCode::kNotFound);
}

TEST(Trajectory, PoseJsonNormalisesAndRejectsBadQuaternions) {
  json pose = {{"translation", {1, 2, 3}}, {"rotation_xyzw", {0, 0, 0, 2}}};
  auto parsed = PoseFromJson(pose, "mount");
  ASSERT_TRUE(parsed.ok()) << parsed.status();
  EXPECT_TRUE(parsed->linear().isApprox(Eigen::Matrix3d::Identity(), 1e-15));
  EXPECT_EQ(parsed->translation(), Eigen::Vector3d(1, 2, 3));
  pose["rotation_xyzw"] = {0, 0, 0, 0.1};
  EXPECT_THAT(PoseFromJson(pose, "mount").status().message(),
              HasSubstr("mount.rotation_xyzw: quaternion norm"));
  pose["rotation_xyzw"] = {0, 0, 3};
  EXPECT_THAT(PoseFromJson(pose, "mount").status().message(),
              HasSubstr("mount.rotation_xyzw: expected [qx, qy, qz, qw]"));
  pose["rotation_xyzw"] = {0, 0, 0, 1};
  pose["translation"] = {1, "x", 3};
  EXPECT_THAT(PoseFromJson(pose, "mount").status().message(), HasSubstr("mount.translation[1]"));
  EXPECT_THAT(PoseFromJson(json::array(), "mount").status().message(),
              HasSubstr("mount: not an object"));
}

TEST(Trajectory, ValidateNamesTheBadElement) {
  struct Case {
    std::function<void(Trajectory&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](Trajectory& t) { t.platform_from_arm_base.linear()(0, 0) = 2; },
       "platform_from_arm_base: rotation is not orthonormal"},
      {[](Trajectory& t) { t.platform_from_arm_base.linear().col(2) *= -1; },
       "platform_from_arm_base: rotation is not orthonormal"},
      {[](Trajectory& t) { t.tool.flange_from_tcp.translation().x() = NAN; },
       "tool.flange_from_tcp: not finite"},
      {[](Trajectory& t) { t.tool.capsules[1].radius = -0.1; },
       "tool.capsules[1].radius: negative"},
      {[](Trajectory& t) { t.tool.capsules[0].a.y() = INFINITY; }, "tool.capsules[0]: not finite"},
      {[](Trajectory& t) { t.segments[1].cut_id = CutId(0); }, "segments[1].cut_id"},
      {[](Trajectory& t) { t.segments[0].points[1].t = 0.0; },
       "segments[0].points[1].t: 0 does not increase"},
      {[](Trajectory& t) { t.segments[1].points[0].t = 0.7; }, "segments[1].points[0].t"},
      {[](Trajectory& t) { t.segments[1].points[1].q[4] = NAN; },
       "segments[1].points[1].q[4]: not finite"},
      {[](Trajectory& t) { t.duration_s = 1.0; }, "duration_s: 1 is less than the last time 1.3"},
      {[](Trajectory& t) { t.duration_s = NAN; }, "duration_s: must be finite"},
      {[](Trajectory& t) { t.unplanned[0].cut_id = CutId(-3); }, "unplanned[0].cut_id"},
      {[](Trajectory& t) { t.unplanned[0].reason.clear(); }, "unplanned[0].reason: empty"},
  };
  for (const Case& c : cases) {
    Trajectory t = SampleTrajectory();
    c.edit(t);
    const absl::Status status = t.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << c.message;
    EXPECT_THAT(status.message(), HasSubstr(c.message));
  }
}

TEST(Trajectory, ASegmentMayStartWhereThePreviousEnded) {
  Trajectory t = SampleTrajectory();
  t.segments[1].points[0].t = t.segments[0].points.back().t;
  t.segments[1].points[0].q = t.segments[0].points.back().q;
  EXPECT_TRUE(t.Validate().ok()) << t.Validate();
}

TEST(Trajectory, FromJsonRejectsMalformedInputNamingTheField) {
  const json good = TrajectoryToJson(SampleTrajectory());
  struct Case {
    std::function<void(json&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](json& j) { j["format"] = "vinebot.cut_plan.v1"; }, "format: expected"},
      {[](json& j) { j["speed"] = 2; }, "speed: unknown field"},
      {[](json& j) { j.erase("robot"); }, "robot: missing"},
      {[](json& j) { j.erase("platform_from_arm_base"); }, "platform_from_arm_base: missing"},
      {[](json& j) { j["platform_from_arm_base"].erase("translation"); },
       "platform_from_arm_base.translation: missing"},
      {[](json& j) { j["tool"]["name"] = 3; }, "tool.name: not a string"},
      {[](json& j) { j["tool"]["mass"] = 3; }, "tool.mass: unknown field"},
      {[](json& j) { j["tool"]["capsules"][0].erase("radius"); },
       "tool.capsules[0].radius: missing"},
      {[](json& j) {
         j["tool"]["capsules"][1]["b"] = {1, 2};
       },
       "tool.capsules[1].b: expected [x, y, z]"},
      {[](json& j) {
         j["tool"]["flange_from_tcp"]["rotation_xyzw"] = {0, 0, 0, 0};
       },
       "tool.flange_from_tcp.rotation_xyzw: quaternion norm"},
      {[](json& j) { j["segments"] = json::object(); }, "segments: not an array"},
      {[](json& j) { j["segments"][0]["kind"] = "jump"; },
       "segments[0].kind: unknown segment kind"},
      {[](json& j) { j["segments"][1].erase("cut_id"); }, "segments[1].cut_id: missing"},
      {[](json& j) { j["segments"][0]["cut_id"] = 4; }, "segments[0].cut_id: only cut segments"},
      {[](json& j) {
         j["segments"][0]["points"][1]["q"] = {1, 2, 3};
       },
       "segments[0].points[1].q: expected 6 joint angles"},
      {[](json& j) { j["segments"][0]["points"][1]["q"][2] = "a"; },
       "segments[0].points[1].q[2]: not a number"},
      {[](json& j) { j["segments"][0]["points"][0].erase("t"); },
       "segments[0].points[0].t: missing"},
      {[](json& j) { j["segments"][1]["points"][0]["t"] = 0.1; },
       "segments[1].points[0].t: 0.1 does not increase"},
      {[](json& j) { j["duration_s"] = "long"; }, "duration_s: not a number"},
      {[](json& j) { j["unplanned"][0]["cut_id"] = "3"; }, "unplanned[0].cut_id: not an integer"},
      {[](json& j) { j["unplanned"][0].erase("reason"); }, "unplanned[0].reason: missing"},
      {[](json& j) { j["unplanned"] = 1; }, "unplanned: not an array"},
  };
  for (const Case& c : cases) {
    json j = good;
    c.edit(j);
    auto t = TrajectoryFromJson(j);
    EXPECT_EQ(t.status().code(), absl::StatusCode::kInvalidArgument) << c.message;
    EXPECT_THAT(t.status().message(), HasSubstr(c.message));
  }
  EXPECT_TRUE(TrajectoryFromJson(good).ok());
}

TEST(Trajectory, EmptyTrajectoryIsValid) {
  Trajectory t;
  EXPECT_TRUE(t.Validate().ok());
  EXPECT_TRUE(TrajectoryFromJson(TrajectoryToJson(t)).ok());
}

}  // namespace
}  // namespace vb
