// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/motion_prover.h"

#include <cmath>
#include <random>

#include "gtest/gtest.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/simple_tool_test_util.h"

namespace vb::plan {
namespace {

// A base rotation of 0.3 rad from a reaching configuration, and a scene of one ball of
// `radius_m` at the flange halfway along it, raised by `offset_m` (0: inside the tool there).
struct Sweep {
  Joints a, b;
  CollisionScene scene;
};

Sweep BaseSweep(double radius_m, double offset_m = 0.0) {
  Sweep s;
  s.a << 0.0, -1.2, 1.4, -1.7, -1.57, 0.0;
  s.b = s.a;
  s.b[0] += 0.3;
  const Eigen::Vector3d centre =
      ForwardKinematics(0.5 * (s.a + s.b)).translation() + Eigen::Vector3d(0, 0, offset_m);
  s.scene.obstacles.push_back(
      {ObstacleKind::kPlatform, 0, Capsule{centre, centre, radius_m}, 0.0});
  return s;
}

MotionProver Prover(const RobotModel& robot, const CollisionScene& scene) {
  return MotionProver(scene, [&robot](const CollisionScene& s) {
    return MakePrimitiveChecker(robot, s);
  });
}

TEST(MotionProver, FindsWhatSamplesStepOver) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  const Sweep s = BaseSweep(0.005);
  auto checker = MakePrimitiveChecker(robot, s.scene);
  ASSERT_TRUE(checker->IsFree(s.a));
  ASSERT_TRUE(checker->IsFree(s.b));
  EXPECT_FALSE(checker->IsMotionFree(s.a, s.b, 0.01));  // the ball is there
  EXPECT_TRUE(checker->IsMotionFree(s.a, s.b, 10.0));   // sampled at the ends only: missed
  MotionProver prover = Prover(robot, s.scene);
  EXPECT_FALSE(prover.IsMotionFree(s.a, s.b));
  EXPECT_FALSE(prover.IsPathFree(std::vector<Joints>{s.a, s.b, s.a}));
  EXPECT_TRUE(prover.IsPathFree(std::vector<Joints>{s.a}));
}

TEST(MotionProver, AgreesWithAVeryDenseCheck) {
  // Random motions past the ball: proven free exactly when a check at 10 micrometres finds them
  // free (they graze the ball closer than that almost never).
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  const Sweep s = BaseSweep(0.004);
  auto reference = MakePrimitiveChecker(robot, s.scene);
  MotionProver prover = Prover(robot, s.scene);
  std::mt19937 rng(1101);
  std::uniform_real_distribution<double> t(0.0, 0.4), dq(-0.15, 0.15);
  int free = 0, colliding = 0;
  for (int i = 0; i < 100; ++i) {
    // From before the ball to after it, shifted sideways in the other joints.
    Joints shift = Joints::Zero();
    for (int j = 1; j < 6; ++j) shift[j] = dq(rng);
    const Joints a = s.a + (s.b - s.a) * t(rng) + shift;
    const Joints b = s.a + (s.b - s.a) * (1.0 - t(rng)) + shift;
    if (!reference->IsFree(a) || !reference->IsFree(b)) continue;
    const bool expected = reference->IsMotionFree(a, b, 1e-5);
    EXPECT_EQ(prover.IsMotionFree(a, b), expected) << "motion " << i;
    (expected ? free : colliding) += 1;
  }
  EXPECT_GT(free, 5);
  EXPECT_GT(colliding, 5);
  EXPECT_GT(prover.checks(), 0);
}

TEST(MotionProver, ProvesAFreeSweepWithFewChecks) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  const Sweep s = BaseSweep(0.005, 0.25);  // far above the flange's way
  auto checker = MakePrimitiveChecker(robot, s.scene);
  ASSERT_TRUE(checker->IsMotionFree(s.a, s.b, 0.001));
  const int64_t dense = checker->checks();
  MotionProver prover = Prover(robot, s.scene);
  EXPECT_TRUE(prover.IsMotionFree(s.a, s.b));
  EXPECT_LT(prover.checks(), dense / 5);  // about the samples at 10 mm
}

TEST(MotionProver, NonFiniteIsNotFree) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  const Sweep s = BaseSweep(0.005, 0.25);
  MotionProver prover = Prover(robot, s.scene);
  Joints bad = s.b;
  bad[2] = std::nan("");
  EXPECT_FALSE(prover.IsMotionFree(s.a, bad));
}


// The sweep's scene with the ball's margin raised by `extra_m`: what a planner with safety
// margins samples in.
CollisionScene WithMargin(const CollisionScene& scene, double extra_m) {
  CollisionScene sampled = scene;
  for (Obstacle& o : sampled.obstacles) o.margin_m += extra_m;
  return sampled;
}

TEST(MotionProverSampled, LeavesToTheSamplingOnlyObstaclesItsMarginsCover) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  Sweep s = BaseSweep(0.005);
  s.scene.planes.push_back({Eigen::Vector3d::UnitZ(), 2.0, 0.0});
  MotionProver prover = Prover(robot, s.scene);
  EXPECT_EQ(prover.unsampled_obstacles(), 1);
  EXPECT_EQ(prover.unsampled_planes(), 1);
  // Not enough margin (below kCoarseStepM / 2 + the slack): the ball is still proven.
  prover.SetSampledScene(WithMargin(s.scene, 0.5 * MotionProver::kCoarseStepM));
  EXPECT_EQ(prover.unsampled_obstacles(), 1);
  EXPECT_FALSE(prover.IsSampledPathFree(std::vector<Joints>{s.a, s.b}));
  // Enough: the ball is the sampling's to prove. The motion hits it, so the caller's check in
  // the sampled scene fails, and IsSampledPathFree, which trusts that check, no longer sees it.
  CollisionScene sampled = WithMargin(s.scene, 0.006);
  prover.SetSampledScene(sampled);
  EXPECT_EQ(prover.unsampled_obstacles(), 0);
  EXPECT_EQ(prover.unsampled_planes(), 1);  // the plane's margin was not raised
  EXPECT_FALSE(MakePrimitiveChecker(robot, sampled)->IsMotionFree(s.a, s.b, 0.01));
  EXPECT_TRUE(prover.IsSampledPathFree(std::vector<Joints>{s.a, s.b}));
  EXPECT_FALSE(prover.IsPathFree(std::vector<Joints>{s.a, s.b}));  // the full proof is unchanged
  // Another obstacle (moved) or another count of obstacles: nothing is covered.
  CollisionScene moved = sampled;
  moved.obstacles[0].capsule.a.x() += 1e-9;
  prover.SetSampledScene(moved);
  EXPECT_EQ(prover.unsampled_obstacles(), 1);
  CollisionScene more = sampled;
  more.obstacles.push_back(more.obstacles[0]);
  prover.SetSampledScene(more);
  EXPECT_EQ(prover.unsampled_obstacles(), 1);
  EXPECT_FALSE(prover.IsSampledPathFree(std::vector<Joints>{s.a, s.b}));
}

TEST(MotionProverSampled, StillProvesTheObstaclesTheMarginsLeaveClose) {
  // The ball the motion hits keeps its own margin in the sampled scene; another, 0.1 m above
  // the flange's way, is covered. The hit ball is still found (the sampled check finds it too).
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  Sweep s = BaseSweep(0.005);
  const Eigen::Vector3d above = s.scene.obstacles[0].capsule.a + Eigen::Vector3d(0, 0, 0.1);
  s.scene.obstacles.push_back({ObstacleKind::kPlatform, 0, Capsule{above, above, 0.002}, 0.0});
  CollisionScene sampled = s.scene;
  sampled.obstacles[1].margin_m = 0.03;
  MotionProver prover = Prover(robot, s.scene);
  prover.SetSampledScene(sampled);
  EXPECT_EQ(prover.unsampled_obstacles(), 1);
  EXPECT_FALSE(prover.IsSampledPathFree(std::vector<Joints>{s.a, s.b}));
  EXPECT_FALSE(prover.IsSampledPathFree(std::vector<Joints>{s.a, s.b, s.a}));
  EXPECT_TRUE(prover.IsSampledPathFree(std::vector<Joints>{s.a}));
  Joints bad = s.b;
  bad[2] = std::nan("");
  EXPECT_FALSE(prover.IsSampledPathFree(std::vector<Joints>{s.a, bad}));
}

TEST(MotionProverSampled, AgreesWithAVeryDenseCheckWhereTheSamplingPassed) {
  // Random motions past a ball 0.1 m above the flange's way, covered by a margin of just over
  // kCoarseStepM / 2 in the sampled scene: wherever the caller's check at 10 mm in the sampled
  // scene passes, the motion is free at 10 micrometres, as IsSampledPathFree (which no longer
  // samples the ball) says. (Without the margin, one of these motions grazes the ball between
  // two samples at 10 mm.)
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  const Sweep s = BaseSweep(0.002, 0.1);
  CollisionScene sampled = s.scene;
  sampled.obstacles[0].margin_m = 0.5 * MotionProver::kCoarseStepM + 2e-6;
  auto sampler = MakePrimitiveChecker(robot, sampled);
  auto reference = MakePrimitiveChecker(robot, s.scene);
  MotionProver prover = Prover(robot, s.scene);
  prover.SetSampledScene(sampled);
  ASSERT_EQ(prover.unsampled_obstacles(), 0);
  std::mt19937 rng(1102);
  std::uniform_real_distribution<double> t(0.0, 0.4), dq(-0.1, 0.1);
  int sampled_free = 0;
  for (int i = 0; i < 600; ++i) {
    Joints shift = Joints::Zero();
    for (int j = 1; j < 6; ++j) shift[j] = dq(rng);
    const Joints a = s.a + (s.b - s.a) * t(rng) + shift;
    const Joints b = s.a + (s.b - s.a) * (1.0 - t(rng)) + shift;
    if (!sampler->IsMotionFree(a, b, MotionProver::kCoarseStepM)) continue;
    ++sampled_free;
    EXPECT_EQ(prover.IsSampledPathFree(std::vector<Joints>{a, b}),
              reference->IsMotionFree(a, b, 1e-5))
        << "motion " << i;
  }
  EXPECT_GT(sampled_free, 50);
}

}  // namespace
}  // namespace vb::plan
