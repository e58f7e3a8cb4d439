// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/motion_choice.h"

#include <cmath>

#include "gtest/gtest.h"
#include "workers/plan/time_parameterization.h"

namespace vb::plan {
namespace {

Joints Q(double a, double b, double c, double d, double e, double f) {
  Joints q;
  q << a, b, c, d, e, f;
  return q;
}

TEST(RollSymmetric, HoldsForBothToolsOfToolH) {
  EXPECT_TRUE(RollSymmetric(DefaultUr5(MillEndTool())));
  EXPECT_TRUE(RollSymmetric(DefaultUr5(SecateurTool())));
}

TEST(RollSymmetric, FailsForAnOffAxisCapsuleOrTcp) {
  ToolGeometry tool = SecateurTool();
  tool.capsules.push_back({Eigen::Vector3d(0.03, 0, 0.05), Eigen::Vector3d(0.03, 0, 0.1), 0.01});
  EXPECT_FALSE(RollSymmetric(DefaultUr5(tool)));
  ToolGeometry offset = MillEndTool();
  offset.flange_from_tcp.translation().x() += 0.01;
  EXPECT_FALSE(RollSymmetric(DefaultUr5(offset)));
  ToolGeometry tilted = MillEndTool();
  tilted.flange_from_tcp.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_FALSE(RollSymmetric(DefaultUr5(tilted)));
}

TEST(RolledTwin, RollsTheTcpFrameByPiAboutItsAxis) {
  const RobotModel robot = DefaultUr5(SecateurTool());
  const std::vector<Joints> path = {Q(0.1, -1.2, 1.3, -0.4, 1.2, 0.3),
                                    Q(0.12, -1.18, 1.28, -0.42, 1.21, 0.31)};
  int twin_index = -1;
  const auto twin =
      RolledTwin(path, 1, CutStroke::kApproachCloseRetract, robot.limits, &twin_index);
  ASSERT_TRUE(twin.has_value());
  ASSERT_EQ(twin->size(), path.size());
  EXPECT_EQ(twin_index, 1);
  for (size_t k = 0; k < path.size(); ++k) {
    const Eigen::Isometry3d tcp = ForwardKinematics(path[k]) * robot.tool.flange_from_tcp;
    const Eigen::Isometry3d rolled = ForwardKinematics((*twin)[k]) * robot.tool.flange_from_tcp;
    EXPECT_LT((tcp.translation() - rolled.translation()).norm(), 1e-9);
    EXPECT_LT((tcp.linear().col(2) - rolled.linear().col(2)).norm(), 1e-9);  // z kept
    EXPECT_LT((tcp.linear().col(1) + rolled.linear().col(1)).norm(), 1e-9);  // y -> -y
    EXPECT_LT((tcp.linear().col(0) + rolled.linear().col(0)).norm(), 1e-9);  // x -> -x
    EXPECT_TRUE(robot.limits.Contains((*twin)[k]));
  }
}

TEST(RolledTwin, ReversesASweepAndStaysWithinTheLimits) {
  JointLimits limits;
  const std::vector<Joints> path = {Q(0, 0, 0, 0, 0, 5.0), Q(0, 0, 0, 0, 0, 5.2),
                                    Q(0, 0, 0, 0, 0, 5.5)};
  int twin_index = -1;
  const auto twin = RolledTwin(path, 0, CutStroke::kSweep, limits, &twin_index);
  ASSERT_TRUE(twin.has_value());
  EXPECT_EQ(twin_index, 2);
  EXPECT_NEAR((*twin)[0][5], 5.5 - M_PI, 1e-12);  // + pi would leave the limit
  EXPECT_NEAR((*twin)[2][5], 5.0 - M_PI, 1e-12);
  // A wrist roll spanning more than the limits allow after a half turn either way: no twin.
  const std::vector<Joints> wide = {Q(0, 0, 0, 0, 0, -5.0), Q(0, 0, 0, 0, 0, 5.0)};
  EXPECT_FALSE(RolledTwin(wide, 0, CutStroke::kSweep, limits, &twin_index).has_value());
  EXPECT_FALSE(RolledTwin({}, 0, CutStroke::kSweep, limits, &twin_index).has_value());
  EXPECT_FALSE(RolledTwin(path, 3, CutStroke::kSweep, limits, &twin_index).has_value());
}

TEST(NearestTurn, TakesTheWholeTurnNearestWithinTheLimits) {
  JointLimits limits;
  limits.lower[2] = -M_PI;
  limits.upper[2] = M_PI;
  const Joints near = Q(3.0, -3.0, 3.0, 0.0, 6.0, 0.0);
  const Joints q = Q(-3.0, 3.0, -3.0, 0.5, -0.5, 6.2);
  const Joints t = NearestTurn(q, near, limits);
  EXPECT_NEAR(t[0], -3.0 + 2 * M_PI, 1e-12);
  EXPECT_NEAR(t[1], 3.0 - 2 * M_PI, 1e-12);
  EXPECT_NEAR(t[2], -3.0, 1e-12);  // the elbow has no whole turn
  EXPECT_NEAR(t[3], 0.5, 1e-12);
  EXPECT_NEAR(t[4], -0.5 + 2 * M_PI, 1e-12);
  EXPECT_NEAR(t[5], 6.2 - 2 * M_PI, 1e-12);
  EXPECT_LT(TurnAwareMoveTimeS(near, q, limits), MoveTimeS(near, q, limits));
  EXPECT_TRUE(SameUpToTurns(q, t));
  EXPECT_FALSE(SameUpToTurns(q, near));
}

}  // namespace
}  // namespace vb::plan
