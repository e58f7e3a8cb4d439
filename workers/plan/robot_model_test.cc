// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/robot_model.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "gtest/gtest.h"
#include "sim/rig.h"
#include "workers/plan/simple_tool_test_util.h"

namespace vb::plan {
namespace {

// Distance of p from the line through `origin` along unit `axis`, and its coordinate along it.
std::pair<double, double> AxisCoordinates(const Eigen::Vector3d& p, const Eigen::Vector3d& origin,
                                          const Eigen::Vector3d& axis) {
  const double along = (p - origin).dot(axis);
  return {(p - origin - along * axis).norm(), along};
}

const Capsule& CapsuleOf(const RobotModel& robot, const std::string& name, int k) {
  for (const LinkBody& body : robot.links) {
    if (body.name == name) return body.capsules.at(k);
  }
  ADD_FAILURE() << "no body " << name;
  static const Capsule none;
  return none;
}

int FrameOf(const RobotModel& robot, const std::string& name) {
  for (const LinkBody& body : robot.links) {
    if (body.name == name) return body.frame;
  }
  return -1;
}

// The capsules run from joint axis to joint axis at the UR5's published offsets, at any q.
TEST(DefaultUr5, CapsulesChainFromJointToJoint) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  std::mt19937 rng(1100);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  for (int trial = 0; trial < 20; ++trial) {
    Joints q;
    for (int i = 0; i < 6; ++i) q[i] = angle(rng);
    const auto f = LinkFrames(q);
    auto world = [&](const std::string& body, int k, bool end_b) {
      const Capsule& c = CapsuleOf(robot, body, k);
      return Eigen::Vector3d(f[FrameOf(robot, body)] * (end_b ? c.b : c.a));
    };
    auto expect_on_axis = [&](const Eigen::Vector3d& p, int joint, double offset) {
      // Joint j (1-based) turns about the z axis of frame j - 1.
      const auto [off_axis, along] =
          AxisCoordinates(p, f[joint - 1].translation(), f[joint - 1].linear().col(2));
      EXPECT_NEAR(off_axis, 0.0, 1e-9) << "joint " << joint;
      EXPECT_NEAR(along, offset, 1e-9) << "joint " << joint;
    };
    // Upper arm: shoulder (joint 2) to elbow (joint 3), 0.13585 m out along both axes.
    expect_on_axis(world("upper_arm", 0, false), 2, 0.13585);
    expect_on_axis(world("upper_arm", 0, true), 3, 0.13585);
    // Elbow housing back to the forearm's plane (elbow offset -0.1197 m).
    expect_on_axis(world("upper_arm", 1, true), 3, 0.13585 - 0.1197);
    // Forearm: elbow to wrist 1 (joint 4) in the forearm's plane, then out along joint 4 to d4.
    expect_on_axis(world("forearm", 0, false), 3, 0.13585 - 0.1197);
    expect_on_axis(world("forearm", 0, true), 4, 0.13585 - 0.1197);
    expect_on_axis(world("forearm", 1, true), 4, 0.10915);
    // Wrist 2 along joint 5 from the joint 4 axis to the joint 6 axis.
    expect_on_axis(world("wrist_2", 0, false), 5, 0.0);
    expect_on_axis(world("wrist_2", 0, true), 5, 0.09465);
    // Wrist 3 along joint 6; its round end reaches the flange.
    const Capsule& w3 = CapsuleOf(robot, "wrist_3", 0);
    const Eigen::Vector3d tip = world("wrist_3", 0, true) + w3.radius * f[6].linear().col(2);
    EXPECT_LT((tip - f[6].translation()).norm(), 1e-9);
    // Shoulder housing from the base axis out to the upper arm.
    expect_on_axis(world("shoulder", 0, false), 2, 0.0);
    expect_on_axis(world("shoulder", 0, true), 2, 0.13585);
  }
}

// Consecutive bodies overlap: the chain of capsules has no gap anywhere.
TEST(DefaultUr5, ConsecutiveBodiesTouch) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  const auto bodies = robot.BodiesWithTool();
  Joints q;
  q << 0.4, -1.1, 1.3, -0.7, 1.2, 0.3;
  const auto f = LinkFrames(q);
  for (size_t b = 0; b + 1 < bodies.size(); ++b) {
    double gap = 1e9;
    for (const Capsule& x : bodies[b].capsules) {
      for (const Capsule& y : bodies[b + 1].capsules) {
        gap = std::min(gap, SegmentSegmentDistance(f[bodies[b].frame] * x.a, f[bodies[b].frame] * x.b,
                                                   f[bodies[b + 1].frame] * y.a,
                                                   f[bodies[b + 1].frame] * y.b) -
                                x.radius - y.radius);
      }
    }
    EXPECT_LT(gap, 0.0) << bodies[b].name << " / " << bodies[b + 1].name;
  }
}

TEST(DefaultUr5, LimitsMountAndRadii) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  ASSERT_TRUE(robot.Validate().ok()) << robot.Validate();
  EXPECT_DOUBLE_EQ(robot.limits.upper[2], M_PI);
  EXPECT_DOUBLE_EQ(robot.limits.lower[2], -M_PI);
  EXPECT_DOUBLE_EQ(robot.limits.upper[0], 2 * M_PI);
  EXPECT_TRUE(robot.platform_from_arm_base.isApprox(DefaultPlatformFromArmBase()));
  // The mount study's mount: 0.45 m in front of the cameras, tilted 50 degrees toward the vine.
  EXPECT_NEAR(robot.platform_from_arm_base.translation().y(), 0.45, 1e-12);
  EXPECT_NEAR((robot.platform_from_arm_base.linear() * Eigen::Vector3d::UnitZ()).z(),
              std::cos(50.0 * M_PI / 180.0), 1e-12);
  EXPECT_NEAR(CapsuleOf(robot, "upper_arm", 0).radius, 0.06, 1e-12);
  EXPECT_NEAR(CapsuleOf(robot, "forearm", 0).radius, 0.06, 1e-12);
  for (const char* wrist : {"wrist_2", "wrist_3"}) {
    EXPECT_GE(CapsuleOf(robot, wrist, 0).radius, 0.0375);
    EXPECT_LE(CapsuleOf(robot, wrist, 0).radius, 0.06);
  }
}

TEST(DefaultUr5, ToolIsTheLastBodyAndSelfPairsSkipNeighbours) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  const auto bodies = robot.BodiesWithTool();
  ASSERT_EQ(bodies.size(), robot.links.size() + 1);
  EXPECT_EQ(bodies.back().frame, 6);
  EXPECT_EQ(bodies.back().capsules.size(), 2u);
  const auto pairs = robot.SelfCollisionPairs();
  EXPECT_FALSE(pairs.empty());
  bool tool_vs_upper_arm = false;
  for (const auto& [i, j] : pairs) {
    EXPECT_GE(std::abs(bodies[i].frame - bodies[j].frame), 2);
    tool_vs_upper_arm |= bodies[i].name == "upper_arm" && j == static_cast<int>(bodies.size()) - 1;
  }
  EXPECT_TRUE(tool_vs_upper_arm);
}

// A straight tool on the joint 6 axis stays at one distance from wrist 2 whatever q is: that pair
// is skipped. A tool bent sideways can reach wrist 2: that pair is checked.
TEST(RobotModel, SelfPairsSkipPairsAtConstantDistance) {
  auto has_pair = [](const RobotModel& robot, const std::string& a, const std::string& b) {
    const auto bodies = robot.BodiesWithTool();
    for (const auto& [i, j] : robot.SelfCollisionPairs()) {
      if (bodies[i].name == a && bodies[j].name == b) return true;
    }
    return false;
  };
  RobotModel straight = DefaultUr5(SimpleMillEnd());
  EXPECT_FALSE(has_pair(straight, "wrist_2", "mill_end"));
  EXPECT_TRUE(has_pair(straight, "forearm", "mill_end"));
  EXPECT_TRUE(has_pair(straight, "shoulder", "forearm"));
  ToolGeometry bent = SimpleMillEnd();
  bent.capsules.push_back({Eigen::Vector3d(0, 0, 0.05), Eigen::Vector3d(0.1, 0, -0.03), 0.02});
  EXPECT_TRUE(has_pair(DefaultUr5(bent), "wrist_2", "mill_end"));
  // The pairs are cached per robot: asking again, after another robot, gives the first answer.
  EXPECT_FALSE(has_pair(straight, "wrist_2", "mill_end"));
  EXPECT_TRUE(has_pair(DefaultUr5(bent), "wrist_2", "mill_end"));
  bent.capsules.back().b.x() = 0.0;  // back on the joint 6 axis: a different robot, pair skipped
  EXPECT_FALSE(has_pair(DefaultUr5(bent), "wrist_2", "mill_end"));
}

TEST(RobotModel, ValidateRejectsBadGeometry) {
  RobotModel robot = DefaultUr5(SimpleMillEnd());
  robot.links[2].capsules[0].radius = -0.01;
  EXPECT_NE(robot.Validate().message().find("links[2]"), std::string::npos);
  robot = DefaultUr5(SimpleMillEnd());
  robot.links[1].frame = 7;
  EXPECT_NE(robot.Validate().message().find("frame"), std::string::npos);
  robot = DefaultUr5(SimpleMillEnd());
  robot.platform_from_arm_base.linear() *= 2.0;
  EXPECT_NE(robot.Validate().message().find("platform_from_arm_base"), std::string::npos);
  robot = DefaultUr5(SimpleMillEnd());
  robot.tool.capsules[0].a.x() = std::nan("");
  EXPECT_NE(robot.Validate().message().find("tool.capsules[0]"), std::string::npos);
  robot = DefaultUr5(SimpleMillEnd());
  robot.limits.lower[2] = 4.0;
  EXPECT_FALSE(robot.Validate().ok());
}

// The planner's camera bodies against the simulator's default rig (sim::MakeRig): workers/plan
// hard-codes them (workers do not depend on sim), so this test ties the two.
TEST(DefaultPlatform, CameraBodiesLieAlongTheDefaultRigsOpticalAxes) {
  const PlatformGeometry platform = DefaultPlatform();
  ASSERT_TRUE(platform.Validate().ok());
  const auto rig = sim::MakeRig();
  ASSERT_TRUE(rig.ok());
  EXPECT_TRUE(platform.fixed_spheres.empty());
  ASSERT_EQ(platform.fixed_capsules.size(), rig->cameras.size());
  for (size_t i = 0; i < rig->cameras.size(); ++i) {
    SCOPED_TRACE(rig->cameras[i].name);
    const Capsule& body = platform.fixed_capsules[i];
    const Eigen::Vector3d centre = rig->cameras[i].CentreInPlatform();
    // The optical axis (camera z) in the platform frame.
    const Eigen::Vector3d optical =
        rig->cameras[i].rotation_camera_from_platform.row(2).transpose().normalized();
    const Eigen::Vector3d along = (body.b - body.a).normalized();
    EXPECT_GT(along.dot(optical), 1.0 - 1e-12);
    const auto [off_axis, behind_a] = AxisCoordinates(centre, body.a, along);
    EXPECT_LT(off_axis, 1e-9);
    // A 0.03 x 0.03 x 0.06 m body behind a lens of 0.03 m diameter and 0.05 m length, the
    // centre of projection anywhere in the lens (from its rear, u = 0, to its front, u = 0.05):
    // every corner of the body and every rim point of the lens is inside the capsule, with at
    // least 0.02 m to spare.
    const Eigen::Vector3d side = optical.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d up = optical.cross(side);
    for (double u : {0.0, 0.025, 0.05}) {
      std::vector<Eigen::Vector3d> points;
      for (double axial : {-u - 0.06, -u}) {
        for (double s : {-0.015, 0.015}) {
          for (double t : {-0.015, 0.015}) points.push_back(centre + axial * optical + s * side + t * up);
        }
      }
      for (double axial : {-u, 0.05 - u}) {
        for (int k = 0; k < 16; ++k) {
          const double angle = M_PI * k / 8;
          points.push_back(centre + axial * optical +
                           0.015 * (std::cos(angle) * side + std::sin(angle) * up));
        }
      }
      for (const Eigen::Vector3d& p : points) {
        EXPECT_LE(PointSegmentDistance(p, body.a, body.b), body.radius - 0.02);
      }
    }
    // Back to the camera-side wall (the bracket), not beyond the lens toward the vine.
    EXPECT_LE(body.a.y() - body.radius, platform.camera_side_wall_y_m);
    EXPECT_LE((body.b - centre).dot(optical), 0.05 + 1e-9);
    EXPECT_GT(behind_a, 0.11);
  }
}

// The camera capsules built from the simulator's default calibration are DefaultPlatform's: the
// plan of a stop with that rig sees the same platform as the tools without a calibration.
TEST(PlatformAroundRig, TheDefaultRigsCalibrationGivesTheDefaultCapsules) {
  const auto rig = sim::MakeRig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  const auto platform = PlatformAroundRig(*rig);
  ASSERT_TRUE(platform.ok()) << platform.status();
  ASSERT_TRUE(platform->Validate().ok());
  const PlatformGeometry nominal = DefaultPlatform();
  EXPECT_EQ(platform->ground_z_m, nominal.ground_z_m);
  EXPECT_EQ(platform->roof_z_m, nominal.roof_z_m);
  EXPECT_EQ(platform->camera_side_wall_y_m, nominal.camera_side_wall_y_m);
  EXPECT_EQ(platform->backdrop_y_m, nominal.backdrop_y_m);
  EXPECT_EQ(platform->fixed_spheres.size(), nominal.fixed_spheres.size());
  ASSERT_EQ(platform->fixed_capsules.size(), nominal.fixed_capsules.size());
  for (size_t i = 0; i < nominal.fixed_capsules.size(); ++i) {
    SCOPED_TRACE(rig->cameras[i].name);
    EXPECT_LT((platform->fixed_capsules[i].a - nominal.fixed_capsules[i].a).norm(), 1e-9);
    EXPECT_LT((platform->fixed_capsules[i].b - nominal.fixed_capsules[i].b).norm(), 1e-9);
    EXPECT_EQ(platform->fixed_capsules[i].radius, nominal.fixed_capsules[i].radius);
  }
}

// A camera mounted 3 cm off nominal and turned 5 degrees moves and turns its capsule with it; the
// others stay put. (3 cm is more than the 2.4 cm the nominal capsule pads the body by.)
TEST(PlatformAroundRig, AMovedCameraMovesItsCapsule) {
  auto rig = sim::MakeRig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  const PlatformGeometry nominal = DefaultPlatform();
  CameraCalibration& cam = rig->cameras[1];
  const Eigen::Vector3d shift(0.03, -0.01, 0.02);
  const Eigen::Vector3d centre = cam.CentreInPlatform() + shift;
  // Turned 5 degrees about platform z, about its own centre: R' = R Rz^T, t' = -R' centre'.
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  cam.rotation_camera_from_platform = cam.rotation_camera_from_platform * turn.transpose();
  cam.translation_camera_from_platform = -cam.rotation_camera_from_platform * centre;
  const auto platform = PlatformAroundRig(*rig);
  ASSERT_TRUE(platform.ok()) << platform.status();
  ASSERT_EQ(platform->fixed_capsules.size(), 3u);
  const Capsule& moved = platform->fixed_capsules[1];
  const Capsule& before = nominal.fixed_capsules[1];
  const Eigen::Vector3d before_axis = (before.b - before.a).normalized();
  const Eigen::Vector3d after_axis = (moved.b - moved.a).normalized();
  EXPECT_NEAR(after_axis.dot(turn * before_axis), 1.0, 1e-9);
  // Nearly 5 degrees from where it was (the axis tilts a little out of the turn's plane).
  EXPECT_GT(std::acos(std::clamp(after_axis.dot(before_axis), -1.0, 1.0)), 4.5 * M_PI / 180.0);
  // The centre of projection lies on the new axis, 0.13 m from its back end, as before.
  const auto [off_axis, behind] = AxisCoordinates(centre, moved.a, after_axis);
  EXPECT_LT(off_axis, 1e-9);
  EXPECT_NEAR(behind, 0.13, 1e-9);
  EXPECT_EQ(moved.radius, before.radius);
  // The nominal capsule no longer holds the camera's centre with the body's 2.1 cm half diagonal
  // to spare: the shift alone exceeds its padding.
  EXPECT_GT(PointSegmentDistance(moved.b, before.a, before.b), 0.02);
  for (size_t i : {0u, 2u}) {
    EXPECT_LT((platform->fixed_capsules[i].a - nominal.fixed_capsules[i].a).norm(), 1e-9);
    EXPECT_LT((platform->fixed_capsules[i].b - nominal.fixed_capsules[i].b).norm(), 1e-9);
  }
}

TEST(PlatformAroundRig, RejectsAnInvalidCalibrationNamingTheCamera) {
  auto rig = sim::MakeRig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  rig->cameras[2].rotation_camera_from_platform(0, 0) = 2.0;
  const auto platform = PlatformAroundRig(*rig);
  EXPECT_EQ(platform.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(platform.status().message().find("cam2"), std::string::npos) << platform.status();
  EXPECT_NE(platform.status().message().find("rotation_camera_from_platform"), std::string::npos);
  EXPECT_EQ(PlatformAroundRig(RigCalibration{}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// A calibration whose camera lies far from every camera of the platform's design (another rig,
// a frame or sign error) would leave the real cameras unprotected: rejected, naming the camera.
TEST(PlatformAroundRig, RejectsACameraFarFromThePlatformsDesign) {
  auto rig = sim::MakeRig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  CameraCalibration& cam = rig->cameras[1];
  const Eigen::Vector3d shift(0.0, 0.0, -0.5);  // centre 0.5 m lower
  cam.translation_camera_from_platform -= cam.rotation_camera_from_platform * shift;
  const auto platform = PlatformAroundRig(*rig);
  EXPECT_EQ(platform.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(platform.status().message().find("cam1"), std::string::npos) << platform.status();
  // Turned around (a sign error in the rotation): rejected, naming the camera.
  auto flipped = sim::MakeRig();
  ASSERT_TRUE(flipped.ok());
  CameraCalibration& f = flipped->cameras[2];
  const Eigen::Vector3d centre = f.CentreInPlatform();
  f.rotation_camera_from_platform =
      Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix() *
      f.rotation_camera_from_platform;
  f.translation_camera_from_platform = -f.rotation_camera_from_platform * centre;
  const auto turned = PlatformAroundRig(*flipped);
  EXPECT_EQ(turned.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(turned.status().message().find("cam2"), std::string::npos) << turned.status();
  EXPECT_NE(turned.status().message().find("degrees"), std::string::npos) << turned.status();
  // 0.1 m off is a rig mounted off its nominal pose: accepted.
  auto near = sim::MakeRig();
  ASSERT_TRUE(near.ok());
  near->cameras[1].translation_camera_from_platform -=
      near->cameras[1].rotation_camera_from_platform * Eigen::Vector3d(0.0, 0.0, -0.1);
  EXPECT_TRUE(PlatformAroundRig(*near).ok());
  // The four-camera study rig (docs/simulator.md, "A fourth camera"): its upper pair lies 0.2 m
  // from the design's apex camera, so the platform's design does not cover it.
  sim::RigOptions four;
  four.camera_count = 4;
  const auto four_platform = PlatformAroundRig(sim::MakeRig(four).value());
  EXPECT_EQ(four_platform.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(four_platform.status().message().find("cam2"), std::string::npos)
      << four_platform.status();
}

TEST(PlatformGeometry, ValidateRejectsBadPlanes) {
  PlatformGeometry platform = DefaultPlatform();
  platform.roof_z_m = -1.0;
  EXPECT_NE(platform.Validate().message().find("roof_z_m"), std::string::npos);
  platform = DefaultPlatform();
  platform.backdrop_y_m = std::nan("");
  EXPECT_NE(platform.Validate().message().find("backdrop_y_m"), std::string::npos);
  platform = DefaultPlatform();
  platform.fixed_spheres = {{Eigen::Vector3d::Zero(), 0.05}, {Eigen::Vector3d::Zero(), -1.0}};
  EXPECT_NE(platform.Validate().message().find("fixed_spheres[1]"), std::string::npos);
  platform = DefaultPlatform();
  platform.fixed_capsules[2].b.x() = std::nan("");
  EXPECT_NE(platform.Validate().message().find("fixed_capsules[2]"), std::string::npos);
}

}  // namespace
}  // namespace vb::plan
