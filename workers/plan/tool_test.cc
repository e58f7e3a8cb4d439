// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/tool.h"

#include <cmath>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace vb::plan {
namespace {

using ::testing::HasSubstr;

double DistanceToCapsuleSurface(const Eigen::Vector3d& p, const Capsule& c) {
  return PointSegmentDistance(p, c.a, c.b) - c.radius;
}

TEST(Tool, MillEndTcpIsInTheMiddleOfTheFlute) {
  const MillEndOptions options;
  ASSERT_TRUE(options.Validate().ok());
  const ToolGeometry tool = MillEndTool(options);
  EXPECT_EQ(tool.name, "mill_end");
  ASSERT_EQ(tool.capsules.size(), 3u);
  const Eigen::Vector3d tcp = tool.flange_from_tcp.translation();
  // On the axis, 0.18 + 0.02 + 0.04 - 0.0125 from the flange, axes as the flange's.
  EXPECT_NEAR(tcp.z(), 0.2275, 1e-12);
  EXPECT_NEAR(tcp.head<2>().norm(), 0.0, 1e-12);
  EXPECT_TRUE(tool.flange_from_tcp.linear().isIdentity(1e-15));
  // The TCP is inside the bit, the bit's tip is half a flute beyond it, the body stays well back.
  const Capsule& bit = tool.capsules[2];
  EXPECT_NEAR(DistanceToCapsuleSurface(tcp, bit), -options.bit_radius_m, 1e-12);
  EXPECT_NEAR(bit.b.z() + bit.radius, tcp.z() + 0.5 * options.flute_length_m, 1e-12);
  EXPECT_GT(DistanceToCapsuleSurface(tcp, tool.capsules[0]), 0.04);
  EXPECT_GT(DistanceToCapsuleSurface(tcp, tool.capsules[1]), 0.01);
  // A 15 mm cane on the TCP touches only the bit.
  EXPECT_GT(DistanceToCapsuleSurface(tcp, tool.capsules[1]), 0.0075);
}

TEST(Tool, SecateurTcpIsBetweenTheOpenJaws) {
  const SecateurOptions options;
  ASSERT_TRUE(options.Validate().ok());
  const ToolGeometry tool = SecateurTool(options);
  EXPECT_EQ(tool.name, "secateur");
  ASSERT_EQ(tool.capsules.size(), 3u);
  const Eigen::Vector3d tcp = tool.flange_from_tcp.translation();
  EXPECT_NEAR(tcp.z(), options.body_length_m + options.tcp_depth_m, 1e-12);
  // Half the opening to each jaw: a cane up to the opening fits.
  EXPECT_NEAR(DistanceToCapsuleSurface(tcp, tool.capsules[1]), 0.5 * options.jaw_opening_m, 1e-12);
  EXPECT_NEAR(DistanceToCapsuleSurface(tcp, tool.capsules[2]), 0.5 * options.jaw_opening_m, 1e-12);
  EXPECT_GT(DistanceToCapsuleSurface(tcp, tool.capsules[0]), 0.0075);
  // The jaws open along TCP x.
  EXPECT_NEAR(tool.capsules[1].a.y(), 0.0, 1e-15);
  EXPECT_NEAR(std::abs(tool.capsules[1].a.x()), 0.5 * options.jaw_opening_m + options.jaw_radius_m,
              1e-15);
}

TEST(Tool, StrokeFollowsTheToolName) {
  EXPECT_EQ(StrokeOf(MillEndTool()), CutStroke::kSweep);
  EXPECT_EQ(StrokeOf(SecateurTool()), CutStroke::kApproachCloseRetract);
}

TEST(Tool, OptionsRejectBadValuesNamingTheField) {
  MillEndOptions mill;
  mill.bit_radius_m = -0.003;
  EXPECT_THAT(mill.Validate().message(), HasSubstr("mill_end.bit_radius_m"));
  mill = MillEndOptions();
  mill.body_length_m = NAN;
  EXPECT_THAT(mill.Validate().message(), HasSubstr("mill_end.body_length_m"));
  mill = MillEndOptions();
  mill.flute_length_m = 0.05;
  EXPECT_THAT(mill.Validate().message(), HasSubstr("mill_end.flute_length_m"));
  mill = MillEndOptions();
  mill.bit_radius_m = 0.02;
  EXPECT_THAT(mill.Validate().message(), HasSubstr("mill_end.bit_radius_m"));
  SecateurOptions secateur;
  secateur.jaw_opening_m = 0.0;
  EXPECT_THAT(secateur.Validate().message(), HasSubstr("secateur.jaw_opening_m"));
  secateur = SecateurOptions();
  secateur.tcp_depth_m = 0.08;
  EXPECT_THAT(secateur.Validate().message(), HasSubstr("secateur.tcp_depth_m"));
}

}  // namespace
}  // namespace vb::plan
