// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/stub_check.h"

#include <cmath>
#include <random>

#include "gtest/gtest.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/motion_choice.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/tool.h"

namespace vb::plan {
namespace {

Joints Q(double a, double b, double c, double d, double e, double f) {
  Joints q;
  q << a, b, c, d, e, f;
  return q;
}

// A stroke-like motion that returns the way it came: q_c + |j| v for j = -6..6.
std::vector<Joints> MirroredMotion(const Joints& q_c, const Joints& v) {
  std::vector<Joints> path;
  for (int j = -6; j <= 6; ++j) path.push_back(q_c + std::abs(j) * v);
  return path;
}

std::vector<Joints> Twin(std::vector<Joints> path) {
  for (Joints& q : path) q[5] += q[5] > 0 ? -M_PI : M_PI;
  return path;
}

// Every configuration and every motion checked: the check before s13.
bool FullyFree(CollisionChecker& checker, const std::vector<Joints>& path) {
  if (!checker.IsFree(path.front())) return false;
  for (size_t i = 1; i < path.size(); ++i)
    if (!checker.IsMotionFree(path[i - 1], path[i], 0.005)) return false;
  return true;
}

TEST(IsMirroredPath, HoldsForAStrokeThatReturnsTheWayItCame) {
  const std::vector<Joints> path = MirroredMotion(Q(0.1, -1.2, 1.3, -0.4, 1.2, 0.3),
                                                  Q(0.01, 0.002, -0.01, 0.003, 0.0, 0.004));
  EXPECT_TRUE(IsMirroredPath(path));
  std::vector<Joints> changed = path;
  changed.back()[2] += 1e-12;
  EXPECT_FALSE(IsMirroredPath(changed));
  changed.pop_back();
  EXPECT_FALSE(IsMirroredPath(changed));  // even size
  EXPECT_FALSE(IsMirroredPath({path[0]}));
}

TEST(IsHalfTurnTwin, FindsTheTwinInEitherOrderAndNothingElse) {
  const std::vector<Joints> path = {Q(0.1, -1.2, 1.3, -0.4, 1.2, 0.3),
                                    Q(0.12, -1.18, 1.28, -0.42, 1.21, 0.31)};
  std::vector<Joints> twin = Twin(path);
  EXPECT_TRUE(IsHalfTurnTwin(path, twin));
  EXPECT_TRUE(IsHalfTurnTwin(twin, path));
  EXPECT_TRUE(IsHalfTurnTwin(path, {twin[1], twin[0]}));  // a sweep's twin runs backwards
  EXPECT_FALSE(IsHalfTurnTwin(path, path));
  std::vector<Joints> off = twin;
  off[1][4] += 1e-12;  // joints 1-5 must be equal bit for bit
  EXPECT_FALSE(IsHalfTurnTwin(path, off));
  off = twin;
  off[0][5] += 1e-6;  // joint 6 turned by pi, not nearly pi
  EXPECT_FALSE(IsHalfTurnTwin(path, off));
  EXPECT_FALSE(IsHalfTurnTwin(path, {twin[0]}));
  off = twin;
  off[1][5] = path[1][5] + (twin[0][5] > path[0][5] ? -M_PI : M_PI);  // the other turn at one
  EXPECT_FALSE(IsHalfTurnTwin(path, off));
}

// The shortcuts (mirrored halves and half-turn twins checked once) never admit a motion that
// touches a stub: on random stubs about the tool along a motion, the verdicts are those of
// checking every configuration and motion of every option.
TEST(KeepMotionsFreeOfStubs, AgreesWithCheckingEveryMotionOnRandomStubs) {
  const RobotModel robot = DefaultUr5(SecateurTool());
  ASSERT_TRUE(RollSymmetric(robot));
  const std::vector<Joints> a = MirroredMotion(Q(0.3, -1.3, 1.6, -1.9, -1.57, 0.4),
                                               Q(0.004, -0.006, 0.01, -0.004, 0.0, 0.002));
  const std::vector<Joints> b = MirroredMotion(Q(-0.2, -1.1, 1.4, -1.6, -1.2, -0.6),
                                               Q(-0.005, 0.004, -0.008, 0.006, 0.003, 0.0));
  std::mt19937 rng(1100);
  std::uniform_real_distribution<double> unit(-1, 1), along(0, 1);
  int kept_all = 0, dropped_some = 0, dropped_all = 0;
  for (int trial = 0; trial < 300; ++trial) {
    // A stub near the tool at a random configuration between two of one motion.
    const std::vector<Joints>& near = trial % 2 ? a : b;
    const size_t i = trial % (near.size() - 1);
    const Joints q = near[i] + along(rng) * (near[i + 1] - near[i]);
    const Eigen::Isometry3d tcp = ForwardKinematics(q) * robot.tool.flange_from_tcp;
    const Eigen::Vector3d centre =
        tcp * Eigen::Vector3d(0.06 * unit(rng), 0.06 * unit(rng), 0.06 * unit(rng) - 0.03);
    const Eigen::Vector3d half(0.01 * unit(rng), 0.01 * unit(rng), 0.01 * unit(rng));
    CollisionScene stubs;
    stubs.obstacles.push_back({ObstacleKind::kCane, 7, {centre - half, centre + half, 0.004}});
    // Now and then a stub on the upper arm of every motion (above the base): nothing is kept.
    if (trial % 25 == 0) stubs.obstacles[0].capsule = {Eigen::Vector3d(0, 0, 0.1),
                                                       Eigen::Vector3d(0, 0, 0.12), 0.05};
    const std::unique_ptr<CollisionChecker> checker = MakePrimitiveChecker(robot, stubs);
    CutMotion motion;
    motion.outcome = CutMotionOutcome::kPlanned;
    motion.path = a;
    motion.alternatives = {Twin(a), b, Twin(b)};
    const std::vector<std::vector<Joints>> options = {a, Twin(a), b, Twin(b)};
    std::vector<std::vector<Joints>> expected;
    for (const auto& option : options)
      if (FullyFree(*checker, option)) expected.push_back(option);
    const bool kept = KeepMotionsFreeOfStubs(*checker, 0.005, /*share_twins=*/true, &motion);
    ASSERT_EQ(kept, !expected.empty()) << "trial " << trial;
    if (!kept) {
      EXPECT_EQ(motion.path, a);  // unchanged
      EXPECT_EQ(motion.alternatives.size(), 3u);
      ++dropped_all;
      continue;
    }
    ASSERT_EQ(1 + motion.alternatives.size(), expected.size()) << "trial " << trial;
    EXPECT_EQ(motion.path, expected[0]);
    for (size_t k = 1; k < expected.size(); ++k) EXPECT_EQ(motion.alternatives[k - 1], expected[k]);
    (expected.size() == options.size() ? kept_all : dropped_some)++;
  }
  // The stubs must have exercised every verdict (else this test could not fail).
  EXPECT_GT(kept_all, 20);
  EXPECT_GT(dropped_some, 20);
  EXPECT_GT(dropped_all, 5);
}

TEST(KeepMotionsFreeOfStubs, WithoutSharingChecksTwinsOnTheirOwn) {
  // A checker that finds every configuration with joint 6 above 2 in collision: a twin is only
  // dropped when it is checked on its own.
  class Joint6Checker : public CollisionChecker {
   public:
    bool IsFree(const Joints& q) override { return q[5] < 2.0; }
    double Clearance(const Joints& q) override { return IsFree(q) ? 1.0 : -1.0; }
  } checker;
  const std::vector<Joints> a = MirroredMotion(Q(0.3, -1.3, 1.6, -1.9, -1.57, -1.0),
                                               Q(0.004, -0.006, 0.01, -0.004, 0.0, 0.002));
  CutMotion motion;
  motion.path = a;
  motion.alternatives = {Twin(a)};  // joint 6 near 2.14
  CutMotion shared = motion;
  ASSERT_TRUE(KeepMotionsFreeOfStubs(checker, 0.005, /*share_twins=*/false, &motion));
  EXPECT_TRUE(motion.alternatives.empty());
  ASSERT_TRUE(KeepMotionsFreeOfStubs(checker, 0.005, /*share_twins=*/true, &shared));
  EXPECT_EQ(shared.alternatives.size(), 1u);  // the twin takes its original's verdict
}

}  // namespace
}  // namespace vb::plan
