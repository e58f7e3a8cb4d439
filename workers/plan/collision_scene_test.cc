// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/collision_scene.h"

#include <algorithm>
#include <cmath>

#include "gtest/gtest.h"
#include "sim/vine_generator.h"

namespace vb::plan {
namespace {

VineModel SimVine(uint64_t seed) {
  sim::VineGeneratorOptions options;
  options.neighbours = false;
  auto scene = sim::GenerateScene(seed, 0, options);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return scene->vine;
}

RobotModel Robot() {
  ToolGeometry tool;
  tool.capsules = {{Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 0.15), 0.03}};
  return DefaultUr5(tool);
}

TEST(CollisionScene, CanesBecomeShortCapsulesInTheBaseFrame) {
  const VineModel vine = SimVine(1100);
  const RobotModel robot = Robot();
  SceneOptions options;
  options.cane_segment_m = 0.03;
  options.default_margin_m = 0.01;
  auto scene = CollisionScene::Build(vine, DefaultPlatform(), robot, options);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  for (const Cane& cane : vine.canes) {
    int count = 0;
    for (const Obstacle& o : scene->obstacles) {
      if (o.kind != ObstacleKind::kCane || o.owner_id != cane.id.value) continue;
      ++count;
      EXPECT_LE((o.capsule.b - o.capsule.a).norm(), 1.6 * options.cane_segment_m);
      EXPECT_DOUBLE_EQ(o.margin_m, 0.01);
      // Each capsule follows the cane closely.
      double distance = 0;
      const Eigen::Vector3d mid_in_platform =
          robot.platform_from_arm_base * (0.5 * (o.capsule.a + o.capsule.b));
      cane.polyline.Project(mid_in_platform, &distance);
      EXPECT_LT(distance, 5e-3);
      EXPECT_LT(o.capsule.radius,
                *std::max_element(cane.polyline.radii.begin(), cane.polyline.radii.end()) + 0.004);
    }
    // The capsules enclose the cane: every sphere along it lies inside one of them.
    const double length = cane.polyline.Length();
    for (double s = 0; s <= length; s += 0.002) {
      const Eigen::Vector3d p = base_from_platform * cane.polyline.PointAt(s);
      double worst = 1e9;
      for (const Obstacle& o : scene->obstacles) {
        if (o.kind != ObstacleKind::kCane || o.owner_id != cane.id.value) continue;
        worst = std::min(worst, PointSegmentDistance(p, o.capsule.a, o.capsule.b) +
                                    cane.polyline.RadiusAt(s) - o.capsule.radius);
      }
      ASSERT_LE(worst, 1e-9) << "cane " << cane.id.value << " s " << s;
    }
    const int expected = std::max<int>(1, std::lround(cane.polyline.Length() / 0.03));
    EXPECT_EQ(count, expected) << "cane " << cane.id.value;
  }
  // The trunk's base, moved into the arm base frame by the mount's inverse, written out.
  const Cane& trunk = vine.canes.front();
  const Eigen::Isometry3d mount = DefaultPlatformFromArmBase();
  EXPECT_LT((base_from_platform * trunk.polyline.points.front() -
             mount.linear().transpose() * (trunk.polyline.points.front() - mount.translation()))
                .norm(),
            1e-12);
  int heads = 0, wires = 0, posts = 0, platform = 0;
  for (const Obstacle& o : scene->obstacles) {
    heads += o.kind == ObstacleKind::kHead;
    wires += o.kind == ObstacleKind::kWire;
    posts += o.kind == ObstacleKind::kPost;
    platform += o.kind == ObstacleKind::kPlatform;
  }
  EXPECT_EQ(heads, static_cast<int>(vine.head.spheres.size()));
  EXPECT_GE(wires, static_cast<int>(vine.wires.size()));
  EXPECT_EQ(posts, static_cast<int>(vine.posts.size()));
  EXPECT_EQ(platform, 3);
}

TEST(CollisionScene, PlanesBoundTheFreeSpace) {
  const RobotModel robot = Robot();
  auto scene = CollisionScene::Build(SimVine(1101), DefaultPlatform(), robot);
  ASSERT_TRUE(scene.ok());
  ASSERT_EQ(scene->planes.size(), 4u);
  auto inside = [&](const Eigen::Vector3d& p_in_platform) {
    const Eigen::Vector3d p = robot.platform_from_arm_base.inverse() * p_in_platform;
    for (const HalfSpace& h : scene->planes) {
      if (h.normal.dot(p) > h.offset) return false;
    }
    return true;
  };
  EXPECT_TRUE(inside(Eigen::Vector3d(0, 0.5, 1.0)));
  EXPECT_FALSE(inside(Eigen::Vector3d(0, 0.5, -0.01)));   // below ground
  EXPECT_FALSE(inside(Eigen::Vector3d(0, 0.5, 2.21)));    // above the roof
  EXPECT_FALSE(inside(Eigen::Vector3d(0, -0.26, 1.0)));   // behind the camera-side wall
  EXPECT_FALSE(inside(Eigen::Vector3d(0, 1.26, 1.0)));    // beyond the backdrop
  EXPECT_TRUE(inside(Eigen::Vector3d(3.0, 1.24, 0.01)));  // x is unbounded along the row
}

TEST(CollisionScene, WithoutCaneNearRemovesOnlyNearCapsulesOfThatCane) {
  const VineModel vine = SimVine(1102);
  const RobotModel robot = Robot();
  auto scene = CollisionScene::Build(vine, DefaultPlatform(), robot);
  ASSERT_TRUE(scene.ok());
  const Cane& cane = vine.canes.at(3);
  const Eigen::Vector3d point =
      robot.platform_from_arm_base.inverse() * cane.polyline.PointAt(0.5 * cane.polyline.Length());
  const CollisionScene cut = scene->WithoutCaneNear(cane.id, point, 0.05);
  ASSERT_LT(cut.obstacles.size(), scene->obstacles.size());
  EXPECT_EQ(cut.planes.size(), scene->planes.size());
  size_t removed_far = 0, kept_near = 0;
  for (const Obstacle& o : scene->obstacles) {
    const bool near = o.kind == ObstacleKind::kCane && o.owner_id == cane.id.value &&
                      PointSegmentDistance(point, o.capsule.a, o.capsule.b) - o.capsule.radius <= 0.05;
    bool kept = false;
    for (const Obstacle& k : cut.obstacles) {
      kept |= k.capsule.a == o.capsule.a && k.capsule.b == o.capsule.b && k.kind == o.kind;
    }
    removed_far += !near && !kept;
    kept_near += near && kept;
  }
  EXPECT_EQ(removed_far, 0u);
  EXPECT_EQ(kept_near, 0u);
  // About 0.1 m of cane (two 0.05 m reaches) in 0.03 m segments.
  EXPECT_GE(scene->obstacles.size() - cut.obstacles.size(), 3u);
  EXPECT_LE(scene->obstacles.size() - cut.obstacles.size(), 6u);
}

TEST(CollisionScene, BuildRejectsBadInput) {
  const RobotModel robot = Robot();
  VineModel vine = SimVine(1103);
  vine.canes[2].polyline.points[1].y() = std::nan("");
  EXPECT_EQ(CollisionScene::Build(vine, DefaultPlatform(), robot).status().code(),
            absl::StatusCode::kInvalidArgument);
  vine = SimVine(1103);
  vine.head.spheres.push_back({Eigen::Vector3d(0, 0, std::nan("")), 0.05});
  EXPECT_NE(CollisionScene::Build(vine, DefaultPlatform(), robot).status().message().find("head"),
            std::string::npos);
  SceneOptions options;
  options.cane_segment_m = 0.0;
  EXPECT_NE(CollisionScene::Build(SimVine(1103), DefaultPlatform(), robot, options)
                .status()
                .message()
                .find("cane_segment_m"),
            std::string::npos);
  options = SceneOptions();
  options.default_margin_m = -0.01;
  EXPECT_NE(options.Validate().message().find("default_margin_m"), std::string::npos);
  PlatformGeometry platform = DefaultPlatform();
  platform.roof_z_m = 0.0;
  EXPECT_FALSE(CollisionScene::Build(SimVine(1103), platform, robot).ok());
}

}  // namespace
}  // namespace vb::plan
