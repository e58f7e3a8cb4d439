// SPDX-License-Identifier: Apache-2.0
#include "core/vine_model_json.h"

#include <unistd.h>

#include <cstdio>
#include <string>

#include "core/capture_metadata.h"
#include "core/json_io.h"
#include "gtest/gtest.h"

namespace vb {
namespace {

using nlohmann::json;

VineModel SmallVine() {
  VineModel m;
  Cane trunk;
  trunk.id = CaneId(1);
  trunk.kind = CaneKind::kTrunk;
  trunk.polyline.points = {{0, 0.8, 0}, {0.01, 0.8, 0.5}, {0, 0.81, 0.9}};
  trunk.polyline.radii = {0.025, 0.022, 0.02};
  Cane cane;
  cane.id = CaneId(2);
  cane.parent_id = CaneId(1);
  cane.polyline.points = {{0, 0.8, 0.9}, {0.3, 0.8, 1.0}, {0.6, 0.82, 0.98}};
  cane.polyline.radii = {0.005, 0.004, 0.003};
  Cane spur = cane;
  spur.id = CaneId(3);
  spur.kind = CaneKind::kSpur;
  spur.parent_id = CaneId(1);
  Cane fork = cane;
  fork.id = CaneId(4);
  fork.parent_id = CaneId(2);
  m.canes = {trunk, cane, spur, fork};
  m.head.spheres = {{Eigen::Vector3d(0, 0.8, 0.92), 0.04}};
  m.wires = {{WireId(1), {{-2, 0.8, 0.95}, {2, 0.8, 0.95}}, 0.0015}};
  m.posts = {{PostId(1), {1.5, 0.8, 0}, {1.5, 0.8, 1.9}, 0.04}};
  return m;
}

TEST(VineModelJson, RoundTripsExactly) {
  const VineModel m = SmallVine();
  ASSERT_TRUE(m.Validate().ok());
  const json j = VineModelToJson(m);
  EXPECT_EQ(j["format"], "vinebot.vine_model.v1");
  EXPECT_EQ(j["canes"][0]["parent_id"], nullptr);
  EXPECT_EQ(j["canes"][2]["kind"], "spur");
  auto back = VineModelFromJson(json::parse(j.dump()));
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->canes.size(), 4u);
  EXPECT_EQ(back->canes[3].parent_id, CaneId(2));
  EXPECT_EQ(back->canes[0].kind, CaneKind::kTrunk);
  EXPECT_EQ(back->canes[1].polyline.points[2], m.canes[1].polyline.points[2]);
  EXPECT_EQ(back->canes[1].polyline.radii, m.canes[1].polyline.radii);
  EXPECT_EQ(back->head.spheres[0].center, m.head.spheres[0].center);
  EXPECT_EQ(back->wires[0].points[1], m.wires[0].points[1]);
  EXPECT_EQ(back->posts[0].top, m.posts[0].top);
  EXPECT_EQ(back->posts[0].radius, 0.04);
}

TEST(VineModelJson, ObstaclesRoundTripExactly) {
  VineModel m = SmallVine();
  WoodObstacle o;
  o.polyline.points = {{0.45, 0.75, 1.1}, {0.62, 0.77, 1.13}, {0.8, 0.8, 1.2}};
  o.polyline.radii = {0.0061, 0.005, 0.0042};
  m.obstacles = {o};
  ASSERT_TRUE(m.Validate().ok());
  const json j = VineModelToJson(m);
  ASSERT_TRUE(j.contains("obstacles"));
  EXPECT_EQ(j["obstacles"].size(), 1u);
  auto back = VineModelFromJson(json::parse(j.dump()));
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->obstacles.size(), 1u);
  EXPECT_EQ(back->obstacles[0].polyline.points, o.polyline.points);
  EXPECT_EQ(back->obstacles[0].polyline.radii, o.polyline.radii);
  EXPECT_EQ(back->canes.size(), m.canes.size());  // obstacles are no canes
}

// Models without obstacles (ground truth, files written before obstacles existed) are written
// without the key, and a file without it reads as a model without obstacles.
TEST(VineModelJson, ObstaclesAreOptional) {
  const json j = VineModelToJson(SmallVine());
  EXPECT_FALSE(j.contains("obstacles"));
  auto back = VineModelFromJson(j);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_TRUE(back->obstacles.empty());
  json empty = j;
  empty["obstacles"] = json::array();
  auto from_empty = VineModelFromJson(empty);
  ASSERT_TRUE(from_empty.ok()) << from_empty.status();
  EXPECT_TRUE(from_empty->obstacles.empty());
  EXPECT_EQ(VineModelToJson(*from_empty), j);
}

TEST(VineModelJson, FileRoundTripAndMissingFile) {
  const std::string path = ::testing::TempDir() + "/vine_model_json_test_" +
                           std::to_string(getpid()) + ".json";
  ASSERT_TRUE(WriteVineModel(path, SmallVine()).ok());
  auto back = ReadVineModel(path);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->canes.size(), 4u);
  std::remove(path.c_str());
  auto missing = ReadVineModel(path);
  EXPECT_EQ(missing.status().code(), absl::StatusCode::kNotFound);
  EXPECT_NE(missing.status().message().find(path), std::string::npos);
}

// Each malformed model must be rejected with INVALID_ARGUMENT and a message naming the problem.
struct BadCase {
  const char* name;
  void (*mutate)(json&);
  const char* expected_in_message;
};

class VineModelJsonRejects : public ::testing::TestWithParam<BadCase> {};

TEST_P(VineModelJsonRejects, MalformedModel) {
  json j = VineModelToJson(SmallVine());
  GetParam().mutate(j);
  auto model = VineModelFromJson(j);
  ASSERT_FALSE(model.ok()) << GetParam().name;
  EXPECT_EQ(model.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(model.status().message().find(GetParam().expected_in_message), std::string::npos)
      << model.status().message();
}

INSTANTIATE_TEST_SUITE_P(
    All, VineModelJsonRejects,
    ::testing::Values(
        BadCase{"format", [](json& j) { j["format"] = "vinebot.vine_model.v0"; }, "format"},
        BadCase{"parent cycle",
                [](json& j) {
                  j["canes"][1]["parent_id"] = 4;  // 2 -> 4 -> 2
                },
                "cycle"},
        BadCase{"unknown parent", [](json& j) { j["canes"][1]["parent_id"] = 77; }, "parent_id 77"},
        BadCase{"nan point", [](json& j) { j["canes"][1]["points"][1][0] = nullptr; },
                "canes[1].points[1][0]"},
        BadCase{"radii mismatch", [](json& j) { j["canes"][2]["radii"].erase(0); },
                "canes[2] (id 3).radii"},
        BadCase{"duplicate id", [](json& j) { j["canes"][2]["id"] = 2; }, "duplicate id"},
        BadCase{"unknown kind", [](json& j) { j["canes"][1]["kind"] = "shoot"; }, "shoot"},
        BadCase{"missing canes", [](json& j) { j.erase("canes"); }, "canes: missing"},
        BadCase{"two trunks", [](json& j) { j["canes"][1]["kind"] = "trunk"; }, "trunks"},
        BadCase{"orphan cane", [](json& j) { j["canes"][1]["parent_id"] = nullptr; },
                "parent_id is null"},
        BadCase{"negative radius", [](json& j) { j["canes"][0]["radii"][0] = -0.01; },
                "radii[0]"},
        BadCase{"bad head sphere", [](json& j) { j["head"]["spheres"][0] = {1, 2, 3}; },
                "head.spheres[0]"},
        BadCase{"wire with one point", [](json& j) { j["wires"][0]["points"].erase(1); },
                "wires[0] (id 1).points"},
        BadCase{"post radius", [](json& j) { j["posts"][0]["radius"] = "big"; },
                "posts[0].radius"},
        BadCase{"obstacles not an array", [](json& j) { j["obstacles"] = json::object(); },
                "obstacles: not an array"},
        BadCase{"obstacle not an object", [](json& j) { j["obstacles"] = {1}; },
                "obstacles[0]: not an object"},
        BadCase{"obstacle with one point",
                [](json& j) {
                  j["obstacles"] = {{{"points", {{0, 0.8, 1}}}, {"radii", {0.004}}}};
                },
                "obstacles[0].points"},
        BadCase{"obstacle radii mismatch",
                [](json& j) {
                  j["obstacles"] = {{{"points", {{0, 0.8, 1}, {0.1, 0.8, 1}}}, {"radii", {0.004}}}};
                },
                "obstacles[0].radii"},
        BadCase{"obstacle without radii",
                [](json& j) { j["obstacles"] = {{{"points", {{0, 0.8, 1}, {0.1, 0.8, 1}}}}}; },
                "obstacles[0].radii"},
        BadCase{"obstacle zero radius",
                [](json& j) {
                  j["obstacles"] = {
                      {{"points", {{0, 0.8, 1}, {0.1, 0.8, 1}}}, {"radii", {0.004, 0.0}}}};
                },
                "obstacles[0].radii[1]"}),
    [](const ::testing::TestParamInfo<BadCase>& info) {
      std::string name = info.param.name;
      for (char& c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      }
      return name;
    });

TEST(VineModelJson, EmptyModelIsValid) {
  auto model = VineModelFromJson(json{{"format", "vinebot.vine_model.v1"}, {"canes", json::array()}});
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_TRUE(model->canes.empty());
}

TEST(ReadJsonFile, RejectsNonJsonNamingTheFile) {
  const std::string path =
      ::testing::TempDir() + "/not_json_" + std::to_string(getpid()) + ".json";
  FILE* f = std::fopen(path.c_str(), "w");
  std::fputs("{\"format\": ", f);
  std::fclose(f);
  auto j = ReadJsonFile(path);
  EXPECT_EQ(j.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(j.status().message().find(path), std::string::npos);
  std::remove(path.c_str());
}

TEST(VineModel, DescendantsAndChildren) {
  const VineModel m = SmallVine();
  EXPECT_EQ(m.ChildrenOf(CaneId(1)).size(), 2u);
  const auto d = m.DescendantsOf(CaneId(1));
  EXPECT_EQ(d.size(), 3u);
  EXPECT_EQ(m.DescendantsOf(CaneId(2)), std::vector<CaneId>{CaneId(4)});
  EXPECT_EQ(m.IndexOf(CaneId(3)), 2u);
}

TEST(CaptureMetadata, RoundTripAndRejections) {
  CaptureMetadata meta;
  meta.row = "row-07";
  meta.vine_position_m = 12.4;
  meta.captured_at = "2026-07-14T09:12:03Z";
  meta.cameras = {{"cam0", "cam0.png", PixelFormat::kRgb8},
                  {"cam1", "cam1.png", PixelFormat::kBayerRg8}};
  auto back = CaptureMetadataFromJson(json::parse(CaptureMetadataToJson(meta).dump()));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->row, "row-07");
  EXPECT_EQ(back->cameras[1].pixel_format, PixelFormat::kBayerRg8);

  json j = CaptureMetadataToJson(meta);
  j["cameras"][1]["pixel_format"] = "yuv422";
  auto bad = CaptureMetadataFromJson(j);
  EXPECT_NE(bad.status().message().find("cameras[1].pixel_format"), std::string::npos)
      << bad.status().message();
  j = CaptureMetadataToJson(meta);
  j["cameras"][0]["image"] = "../etc/passwd";
  EXPECT_NE(CaptureMetadataFromJson(j).status().message().find("cameras[0].image"),
            std::string::npos);
  j = CaptureMetadataToJson(meta);
  j["cameras"][1]["name"] = "cam0";
  EXPECT_NE(CaptureMetadataFromJson(j).status().message().find("duplicate"), std::string::npos);
  j = CaptureMetadataToJson(meta);
  j.erase("vine_position_m");
  EXPECT_NE(CaptureMetadataFromJson(j).status().message().find("vine_position_m"),
            std::string::npos);
  EXPECT_EQ(UtcNowIso8601().size(), 20u);
}

}  // namespace
}  // namespace vb
