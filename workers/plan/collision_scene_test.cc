// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/collision_scene.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/plan/fallen_wood.h"

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
    const int expected = std::max<int>(1, std::ceil(cane.polyline.Length() / 0.03 - 1e-6));
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

TEST(CollisionScene, CaneChordEndsAreThePolylinesOwnPointsBitForBit) {
  // The chords are located on arc lengths computed once per cane; they must be the points and
  // radii Polyline3::PointAt and RadiusAt give, to the last bit (plans are compared bit for bit
  // between builds).
  const RobotModel robot = Robot();
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  for (uint64_t seed : {1100u, 1101u}) {
    const VineModel vine = SimVine(seed);
    for (double step : {0.03, 0.011}) {
      SceneOptions options;
      options.cane_segment_m = step;
      auto scene = CollisionScene::Build(vine, DefaultPlatform(), robot, options);
      ASSERT_TRUE(scene.ok()) << scene.status();
      for (const Cane& cane : vine.canes) {
        std::vector<const Obstacle*> chords;
        for (const Obstacle& o : scene->obstacles)
          if (o.kind == ObstacleKind::kCane && o.owner_id == cane.id.value) chords.push_back(&o);
        ASSERT_FALSE(chords.empty());
        const double length = cane.polyline.Length();
        for (size_t k = 0; k < chords.size(); ++k) {
          const double s0 = k * step;
          const double s1 = k + 1 == chords.size() ? length : (k + 1) * step;
          const Eigen::Vector3d a = base_from_platform * cane.polyline.PointAt(s0);
          const Eigen::Vector3d b = base_from_platform * cane.polyline.PointAt(s1);
          EXPECT_TRUE(chords[k]->capsule.a == a && chords[k]->capsule.b == b)
              << "seed " << seed << " cane " << cane.id.value << " chord " << k;
          EXPECT_GE(chords[k]->capsule.radius,
                    std::max(cane.polyline.RadiusAt(s0), cane.polyline.RadiusAt(s1)));
        }
      }
    }
  }
}

TEST(CollisionScene, ACaneCutShortKeepsItsCapsules) {
  // Chords start from the base on a fixed grid: after a cut, the stub has the capsules it had up
  // to the cut; only the one the cut falls in differs, and it stays within a fraction of a
  // millimetre of the uncut cane's capsule there (its chord ends at the cut, where the cane may
  // bend away from the uncut chord, and its radius is its thicker end's). So a motion free on
  // the uncut vine is free on the cut one except within that fraction of a millimetre of the
  // cut end. (With equally spaced chords every chord of the stub moved, by up to 0.7 mm.)
  const VineModel vine = SimVine(1101);
  const RobotModel robot = Robot();
  const SceneOptions options;
  auto full = CollisionScene::Build(vine, DefaultPlatform(), robot, options);
  ASSERT_TRUE(full.ok()) << full.status();
  auto capsules_of = [](const CollisionScene& scene, int64_t id) {
    std::vector<Capsule> out;
    for (const Obstacle& o : scene.obstacles)
      if (o.kind == ObstacleKind::kCane && o.owner_id == id) out.push_back(o.capsule);
    return out;
  };
  int stubs = 0;
  for (size_t c = 0; c < vine.canes.size(); ++c) {
    const std::vector<Capsule> whole = capsules_of(*full, vine.canes[c].id.value);
    const double length = vine.canes[c].polyline.Length();
    for (double f : {0.13, 0.5, 0.77}) {
      VineModel cut = vine;
      cut.canes[c].polyline.TruncateAt(f * length);
      auto scene = CollisionScene::Build(cut, DefaultPlatform(), robot, options);
      ASSERT_TRUE(scene.ok()) << scene.status();
      const std::vector<Capsule> stub = capsules_of(*scene, vine.canes[c].id.value);
      ASSERT_LE(stub.size(), whole.size());
      for (size_t k = 0; k + 1 < stub.size(); ++k) {
        EXPECT_LT((stub[k].a - whole[k].a).norm(), 1e-9);
        EXPECT_LT((stub[k].b - whole[k].b).norm(), 1e-9);
        EXPECT_NEAR(stub[k].radius, whole[k].radius, 1e-9);
      }
      // The last one: every sphere along its axis inside the uncut cane's capsule there.
      const Capsule& last = stub.back();
      const Capsule& around = whole[stub.size() - 1];
      for (double t = 0; t <= 1.0; t += 0.05) {
        const Eigen::Vector3d p = last.a + t * (last.b - last.a);
        EXPECT_LE(PointSegmentDistance(p, around.a, around.b) + last.radius, around.radius + 1e-3)
            << "cane " << c << " cut at " << f;
      }
      ++stubs;
    }
  }
  EXPECT_GT(stubs, 10);
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
  vine = SimVine(1103);
  vine.canes[2].polyline.points[1].x() = 1e9;  // finite, absurd: no chord grid of it is built
  EXPECT_NE(CollisionScene::Build(vine, DefaultPlatform(), robot).status().message().find(
                "canes[2].points"),
            std::string::npos);
  vine = SimVine(1103);
  vine.obstacles.push_back({vine.canes[2].polyline});
  vine.obstacles[0].polyline.points[0].z() = -1e9;
  EXPECT_NE(CollisionScene::Build(vine, DefaultPlatform(), robot).status().message().find(
                "obstacles[0].points"),
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


// Overlap depth of a point with the scene's capsules (> 0: inside one).
double Depth(const CollisionScene& scene, const Eigen::Vector3d& p) {
  double depth = -1e9;
  for (const Obstacle& o : scene.obstacles)
    depth = std::max(depth, o.capsule.radius - PointSegmentDistance(p, o.capsule.a, o.capsule.b));
  return depth;
}

bool Holds(const std::vector<Obstacle>& in, const Obstacle& o) {
  return std::any_of(in.begin(), in.end(), [&](const Obstacle& x) {
    return x.kind == o.kind && x.owner_id == o.owner_id && x.capsule.a == o.capsule.a &&
           x.capsule.b == o.capsule.b && x.capsule.radius == o.capsule.radius;
  });
}

TEST(StubChords, AStubChordThatBulgesOutOfTheUncutCaneIsInTheUnion) {
  // A thick cane kinked 3 mm up between two grid points (0.03 m chords), cut at the kink: the
  // stub's last chord ends there with the radius of its thick end, so it reaches a point 7 mm
  // above the kink that the uncut chord (radius 8 mm about its axis, 10 mm away) leaves free. A
  // motion planned on the uncut vine may pass there and touch the stub once the cut is made.
  const RobotModel robot = Robot();
  const Eigen::Vector3d base(0.0, 0.5, 1.0);
  VineModel vine;
  Cane trunk;
  trunk.id = CaneId{1};
  trunk.kind = CaneKind::kTrunk;
  trunk.polyline.points = {Eigen::Vector3d(0, 0.5, 0), base};
  trunk.polyline.radii = {0.02, 0.02};
  Cane cane;
  cane.id = CaneId{2};
  cane.parent_id = trunk.id;
  const Eigen::Vector3d kink = base + Eigen::Vector3d(0.045, 0, 0.003);
  cane.polyline.points = {base, base + Eigen::Vector3d(0.03, 0, 0), kink,
                          base + Eigen::Vector3d(0.06, 0, 0), base + Eigen::Vector3d(0.3, 0, 0)};
  cane.polyline.radii = {0.009, 0.008, 0.004, 0.004, 0.003};
  vine.canes = {trunk, cane};
  Cut cut;
  cut.id = CutId{1};
  cut.cane_id = cane.id;
  cut.point = kink;
  cut.direction = Eigen::Vector3d::UnitX();
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  const Eigen::Vector3d p = base_from_platform * (kink + Eigen::Vector3d(0, 0, 0.007));

  auto uncut = CollisionScene::Build(vine, DefaultPlatform(), robot);
  auto after = CollisionScene::Build(WithoutFallenWood(vine, {&cut, 1}), DefaultPlatform(), robot);
  ASSERT_TRUE(uncut.ok() && after.ok());
  EXPECT_LT(Depth(*uncut, p), -0.001);  // free by a millimetre on the uncut vine
  EXPECT_GT(Depth(*after, p), 0.0005);  // inside the stub once the cut is made

  auto stub = StubChords(vine, {}, cut, robot);
  ASSERT_TRUE(stub.ok()) << stub.status();
  ASSERT_EQ(stub->size(), 1u);  // only the chord the cut falls in differs
  CollisionScene pass = *uncut;
  pass.obstacles.insert(pass.obstacles.end(), stub->begin(), stub->end());
  EXPECT_GT(Depth(pass, p), 0.0005);
  for (const Obstacle& o : after->obstacles) EXPECT_TRUE(Holds(pass.obstacles, o));

  // A cut at the very base takes the whole cane: no stub.
  Cut at_base = cut;
  at_base.point = base;
  auto none = StubChords(vine, {}, at_base, robot);
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE(none->empty());
}

TEST(StubChords, TheSceneAndTheStubsHoldEveryStateOfThePass) {
  // Cuts at 30% and 60% of every cane of simulated vines; a third of them made before the pass.
  // The scene of the vine after those, with the stubs of the rest, holds every obstacle of the
  // vine after any subset of the rest; the scene alone does not.
  const RobotModel robot = Robot();
  std::mt19937 rng(1104);
  int missing_without_stubs = 0, states = 0;
  for (uint64_t seed : {1100, 1101, 1102}) {
    const VineModel vine = SimVine(seed);
    std::vector<Cut> made, pass;
    int id = 0;
    for (const Cane& cane : vine.canes) {
      if (cane.kind == CaneKind::kTrunk) continue;
      for (double f : {0.3, 0.6}) {
        Cut cut;
        cut.id = CutId{++id};
        cut.cane_id = cane.id;
        cut.point = cane.polyline.PointAt(f * cane.polyline.Length());
        (id % 3 == 0 ? made : pass).push_back(cut);
      }
    }
    auto start = CollisionScene::Build(WithoutFallenWood(vine, made), DefaultPlatform(), robot);
    ASSERT_TRUE(start.ok()) << start.status();
    CollisionScene union_scene = *start;
    for (const Cut& cut : pass) {
      auto stub = StubChords(vine, made, cut, robot);
      ASSERT_TRUE(stub.ok()) << stub.status();
      union_scene.obstacles.insert(union_scene.obstacles.end(), stub->begin(), stub->end());
    }
    for (int trial = 0; trial < 12; ++trial) {
      std::vector<Cut> now = made;
      for (const Cut& cut : pass)
        if (std::bernoulli_distribution(trial < 2 ? 1.0 : 0.3)(rng)) now.push_back(cut);
      auto scene = CollisionScene::Build(WithoutFallenWood(vine, now), DefaultPlatform(), robot);
      ASSERT_TRUE(scene.ok()) << scene.status();
      ++states;
      for (const Obstacle& o : scene->obstacles) {
        EXPECT_TRUE(Holds(union_scene.obstacles, o)) << "seed " << seed << " cane " << o.owner_id;
        missing_without_stubs += !Holds(start->obstacles, o);
      }
    }
  }
  EXPECT_EQ(states, 36);
  EXPECT_GT(missing_without_stubs, 0);
}

TEST(StubChords, RejectsBadInput) {
  const RobotModel robot = Robot();
  const VineModel vine = SimVine(1103);
  Cut cut;
  cut.cane_id = vine.canes.back().id;
  cut.point = Eigen::Vector3d(0, std::nan(""), 0);
  auto result = StubChords(vine, {}, cut, robot);
  EXPECT_EQ(result.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(result.status().message().find("cut.point"), std::string::npos);
  cut.point = vine.canes.back().polyline.points.front();
  SceneOptions options;
  options.cane_segment_m = -1;
  EXPECT_NE(StubChords(vine, {}, cut, robot, options).status().message().find("cane_segment_m"),
            std::string::npos);
}

}  // namespace
}  // namespace vb::plan
