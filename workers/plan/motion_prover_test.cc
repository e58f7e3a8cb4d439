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

}  // namespace
}  // namespace vb::plan
