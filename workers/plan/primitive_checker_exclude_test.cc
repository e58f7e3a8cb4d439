// SPDX-License-Identifier: Apache-2.0
// What cut_motion.cc relies on to reuse one primitive checker for every cut and slide
// (PrimitiveChecker::Exclude answers as a checker built on the scene without the excluded
// obstacles) and to check each stroke configuration once (IsMotionInteriorFree).
#include <algorithm>
#include <memory>
#include <random>
#include <span>
#include <vector>

#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/plan/primitive_checker.h"
#include "workers/plan/tool.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {
namespace {

CollisionScene VineScene(uint64_t seed, const RobotModel& robot) {
  sim::VineGeneratorOptions options;
  options.neighbours = false;
  auto sim_scene = sim::GenerateScene(seed, 0, options);
  EXPECT_TRUE(sim_scene.ok()) << sim_scene.status();
  auto scene = CollisionScene::Build(sim_scene->vine, DefaultPlatform(), robot);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return *scene;
}

// Configurations with the TCP on `point` (random tool orientations, every IK branch), and a
// motion from each to a nearby random configuration.
std::vector<Joints> ConfigurationsAt(const RobotModel& robot, const Eigen::Vector3d& point,
                                     std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<Joints> out;
  for (int i = 0; i < 40; ++i) {
    Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
    tcp.linear() = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng))
                       .normalized()
                       .toRotationMatrix();
    tcp.translation() = point;
    const IkSolutions ik =
        InverseKinematics(tcp * robot.tool.flange_from_tcp.inverse(), robot.limits);
    for (int k = 0; k < ik.count; ++k) out.push_back(ik.q[k]);
  }
  return out;
}

TEST(PrimitiveCheckerExclude, AnswersAsACheckerBuiltWithoutTheObstacles) {
  const RobotModel robot = DefaultUr5(SecateurTool());
  std::mt19937 rng(1106);
  std::uniform_real_distribution<double> step(-0.05, 0.05);
  int differ_from_full = 0, compared = 0;
  for (uint64_t seed : {1106, 1107}) {
    const CollisionScene scene = VineScene(seed, robot);
    PrimitiveChecker shared(robot, scene);
    PrimitiveChecker full(robot, scene);
    // Three canes in turn, then none: each exclusion replaces the one before.
    std::vector<int64_t> canes;
    for (const Obstacle& o : scene.obstacles)
      if (o.kind == ObstacleKind::kCane &&
          std::find(canes.begin(), canes.end(), o.owner_id) == canes.end())
        canes.push_back(o.owner_id);
    ASSERT_GE(canes.size(), 3u);
    for (int round = 0; round < 4; ++round) {
      std::vector<int> excluded;
      CollisionScene reduced = scene;
      Eigen::Vector3d point = Eigen::Vector3d::Zero();
      if (round < 3) {
        const int64_t cane = canes[canes.size() * round / 3];
        for (const Obstacle& o : scene.obstacles)
          if (o.owner_id == cane && o.kind == ObstacleKind::kCane) point = o.capsule.a;
        reduced = scene.WithoutCaneNear(CaneId{cane}, point, 0.04);
        for (size_t i = 0; i < scene.obstacles.size(); ++i) {
          const Obstacle& o = scene.obstacles[i];
          if (o.kind == ObstacleKind::kCane && o.owner_id == cane &&
              PointSegmentDistance(point, o.capsule.a, o.capsule.b) - o.capsule.radius <= 0.04)
            excluded.push_back(static_cast<int>(i));
        }
        ASSERT_FALSE(excluded.empty());
        ASSERT_EQ(reduced.obstacles.size() + excluded.size(), scene.obstacles.size());
        // The scene's own index list is the same rule (ascending, the complement of `reduced`).
        EXPECT_EQ(scene.CaneNearIndices(CaneId{cane}, point, 0.04), excluded);
      } else {
        point = scene.obstacles[excluded.size()].capsule.a;  // any cane point
      }
      shared.Exclude(excluded);
      PrimitiveChecker fresh(robot, reduced);
      const std::vector<Joints> qs = ConfigurationsAt(robot, point, rng);
      ASSERT_GT(qs.size(), 20u);
      std::vector<char> free_shared(qs.size()), free_fresh(qs.size());
      std::unique_ptr<bool[]> a(new bool[qs.size()]), b(new bool[qs.size()]);
      shared.AreFree(qs, std::span<bool>(a.get(), qs.size()));
      fresh.AreFree(qs, std::span<bool>(b.get(), qs.size()));
      for (size_t i = 0; i < qs.size(); ++i) {
        const Joints& q = qs[i];
        Joints to = q;
        for (int j = 0; j < 6; ++j) to[j] += step(rng);
        // Bit for bit: the same pieces, the same min.
        ASSERT_EQ(shared.Clearance(q), fresh.Clearance(q)) << "seed " << seed << " i " << i;
        const double above = fresh.ClearanceAbove(q, 0.001, 0.02);
        if (above > 0.001) ASSERT_EQ(shared.ClearanceAbove(q, 0.001, 0.02), above);
        else ASSERT_LE(shared.ClearanceAbove(q, 0.001, 0.02), 0.001);
        ASSERT_EQ(shared.IsFree(q), fresh.IsFree(q)) << "seed " << seed << " i " << i;
        ASSERT_EQ(a[i], b[i]) << "seed " << seed << " i " << i;
        ASSERT_EQ(shared.IsMotionFree(q, to, 0.005), fresh.IsMotionFree(q, to, 0.005));
        differ_from_full += full.IsFree(q) != shared.IsFree(q);
        ++compared;
      }
    }
  }
  // The exclusions mattered (else this test could not fail).
  EXPECT_GT(differ_from_full, 5) << "of " << compared;
}

}  // namespace
}  // namespace vb::plan

namespace vb::plan {
namespace {

// IsMotionInteriorFree with the ends checked by AreFree is IsMotionFree, verdict for verdict.
TEST(PrimitiveCheckerInterior, WithTheEndsFromAreFreeIsIsMotionFree) {
  const RobotModel robot = DefaultUr5(SecateurTool());
  const CollisionScene scene = VineScene(1108, robot);
  PrimitiveChecker checker(robot, scene);
  std::mt19937 rng(1108);
  std::uniform_real_distribution<double> step(-0.08, 0.08);
  int free = 0, blocked_inside = 0, blocked_at_ends = 0;
  for (int round = 0; round < 6; ++round) {
    const Eigen::Vector3d point = scene.obstacles[(round * 37) % scene.obstacles.size()].capsule.a;
    for (const Joints& a : ConfigurationsAt(robot, point + Eigen::Vector3d(0, -0.05, 0), rng)) {
      Joints b = a;
      for (int j = 0; j < 6; ++j) b[j] += step(rng);
      const Joints ends[2] = {a, b};
      bool ends_free[2];
      checker.AreFree(ends, ends_free);
      const bool interior = checker.IsMotionInteriorFree(a, b, 0.005);
      ASSERT_EQ(checker.IsMotionFree(a, b, 0.005), ends_free[0] && ends_free[1] && interior);
      if (!(ends_free[0] && ends_free[1])) ++blocked_at_ends;
      else (interior ? free : blocked_inside)++;
    }
  }
  // Every kind of motion was met (else this test could not fail).
  EXPECT_GT(free, 10);
  EXPECT_GT(blocked_inside, 3);
  EXPECT_GT(blocked_at_ends, 10);
}

}  // namespace
}  // namespace vb::plan
