// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/ur5_kinematics.h"

#include <cmath>

#include "gtest/gtest.h"

namespace vb::plan {
namespace {

// At q = 0 the UR5 lies stretched along -x of the base: flange at
// x = a2 + a3, y = -(d4 + d6), z = d1 - d5 (ur_kinematics' zero pose).
TEST(Ur5Kinematics, ZeroConfigurationMatchesDhTable) {
  const Eigen::Isometry3d flange = ForwardKinematics(Joints::Zero());
  EXPECT_NEAR(flange.translation().x(), -0.425 - 0.39225, 1e-12);
  EXPECT_NEAR(flange.translation().y(), -(0.10915 + 0.0823), 1e-12);
  EXPECT_NEAR(flange.translation().z(), 0.089159 - 0.09465, 1e-12);
}

TEST(Ur5Kinematics, LinkFramesEndAtTheFlange) {
  Joints q;
  q << 0.3, -1.2, 1.0, -0.4, 0.7, 2.0;
  const auto frames = LinkFrames(q);
  EXPECT_TRUE(frames[0].isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(frames[6].isApprox(ForwardKinematics(q), 1e-12));
  // Joint 1 rotates about the base z axis only: the shoulder frame sits at height d1.
  EXPECT_NEAR(frames[1].translation().z(), 0.089159, 1e-12);
}

TEST(Ur5Kinematics, LimitsRejectBadValues) {
  JointLimits limits;
  EXPECT_TRUE(limits.Validate().ok());
  limits.upper[2] = limits.lower[2];
  EXPECT_NE(limits.Validate().message().find("joint 3"), std::string::npos);
  limits = JointLimits();
  limits.max_velocity[0] = 0.0;
  EXPECT_FALSE(limits.Validate().ok());
}

}  // namespace
}  // namespace vb::plan
