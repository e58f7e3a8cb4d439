// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/cut_motion.h"

// Cut motions on small synthetic scenes (a cane, balls, walls) against a brute-force checker: pose
// sampling, strokes, rolls, tilts, slides, failures and bad input. The simulated vines are in
// cut_motion_vines_test.cc.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "workers/plan/tool.h"

namespace vb::plan {
namespace {

using ::testing::HasSubstr;

// A brute-force checker, independent of the real one: every arm capsule against every obstacle
// capsule (inflated by its margin) and plane, no self-collision, no culling.
class BruteForceChecker : public CollisionChecker {
 public:
  BruteForceChecker(const RobotModel& robot, const CollisionScene& scene)
      : bodies_(robot.links), scene_(scene) {
    bodies_.push_back({"tool", 6, robot.tool.capsules});
  }
  bool IsFree(const Joints& q) override { return Clearance(q) > 0; }
  double Clearance(const Joints& q) override {
    ++checks_;
    const auto frames = LinkFrames(q);
    double clearance = std::numeric_limits<double>::infinity();
    for (const LinkBody& body : bodies_) {
      for (const Capsule& c : body.capsules) {
        const Eigen::Vector3d a = frames[body.frame] * c.a, b = frames[body.frame] * c.b;
        for (const Obstacle& o : scene_.obstacles) {
          clearance = std::min(clearance, SegmentSegmentDistance(a, b, o.capsule.a, o.capsule.b) -
                                              c.radius - o.capsule.radius - o.margin_m);
        }
        for (const HalfSpace& h : scene_.planes) {
          const double reach = std::max(h.normal.dot(a), h.normal.dot(b)) + c.radius;
          clearance = std::min(clearance, h.offset - h.margin_m - reach);
        }
      }
    }
    return clearance;
  }

 private:
  std::vector<LinkBody> bodies_;
  CollisionScene scene_;
};

std::unique_ptr<CollisionChecker> MakeBruteForce(const RobotModel& robot,
                                                 const CollisionScene& scene) {
  return std::make_unique<BruteForceChecker>(robot, scene);
}

// A coarse UR5: one capsule from each DH frame origin back to the previous one (its position in
// frame i+1 does not depend on q), radius 0.04; the shoulder and elbow offsets are ignored.
RobotModel TestRobot(const ToolGeometry& tool) {
  RobotModel robot;
  robot.tool = tool;
  // Base frame 0.35 m across the row from the cameras, 0.6 m up, x along -y of the platform.
  robot.platform_from_arm_base.translation() << 0.0, 0.35, 0.6;
  robot.platform_from_arm_base.linear() =
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const DhParameters& dh = Ur5Dh();
  for (int i = 1; i < 6; ++i) {
    const Eigen::Vector3d previous = Eigen::AngleAxisd(-dh.alpha[i], Eigen::Vector3d::UnitX()) *
                                     Eigen::Vector3d(-dh.a[i], 0, -dh.d[i]);
    robot.links.push_back({"link", i + 1, {{Eigen::Vector3d::Zero(), previous, 0.04}}});
  }
  return robot;
}

constexpr int64_t kCutCane = 2;

// A vertical cane in the vine plane (platform frame), cut at z = 0.95; a second cane 0.25 m
// along the row; the ground. `extra` obstacles are given in the platform frame.
struct TestWorld {
  VineModel model;
  CollisionScene scene;  // arm base frame
  Cut cut;
};

TestWorld MakeWorld(const RobotModel& robot, const std::vector<Obstacle>& extra = {}) {
  TestWorld w;
  for (int64_t id : {kCutCane, int64_t{3}}) {
    Cane cane;
    cane.id = CaneId(id);
    const double x = id == kCutCane ? 0.05 : 0.30;
    for (int k = 0; k <= 20; ++k) {
      cane.polyline.points.push_back(Eigen::Vector3d(x, 0.8, 0.7 + 0.5 * k / 20));
      cane.polyline.radii.push_back(0.005);
    }
    w.model.canes.push_back(cane);
  }
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  for (const Cane& cane : w.model.canes) {
    const auto& p = cane.polyline.points;
    for (size_t k = 1; k < p.size(); ++k) {
      Obstacle o;
      o.kind = ObstacleKind::kCane;
      o.owner_id = cane.id.value;
      o.capsule = {base_from_platform * p[k - 1], base_from_platform * p[k], 0.005};
      w.scene.obstacles.push_back(o);
    }
  }
  for (Obstacle o : extra) {
    o.capsule.a = base_from_platform * o.capsule.a;
    o.capsule.b = base_from_platform * o.capsule.b;
    w.scene.obstacles.push_back(o);
  }
  HalfSpace ground;  // platform z >= 0
  ground.normal = base_from_platform.linear() * Eigen::Vector3d(0, 0, -1);
  ground.offset = ground.normal.dot(base_from_platform.translation());
  w.scene.planes.push_back(ground);
  w.cut.id = CutId(1);
  w.cut.cane_id = CaneId(kCutCane);
  w.cut.point = Eigen::Vector3d(0.05, 0.8, 0.95);
  w.cut.direction = Eigen::Vector3d::UnitZ();
  w.cut.diameter_m = 0.01;
  return w;
}

Obstacle Ball(const Eigen::Vector3d& center_in_platform, double radius) {
  Obstacle o;
  o.kind = ObstacleKind::kHead;
  o.capsule = {center_in_platform, center_in_platform, radius};
  return o;
}

Eigen::Isometry3d TcpInBase(const RobotModel& robot, const Joints& q) {
  return ForwardKinematics(q) * robot.tool.flange_from_tcp;
}

TEST(StrokeWaypoints, SweepIsCentredOnTheCut) {
  CutMotionOptions options;
  int cut_index = -1;
  const auto sweep = StrokeWaypoints(CutStroke::kSweep, options, &cut_index);
  ASSERT_EQ(sweep.size(), 21u);
  EXPECT_EQ(cut_index, 10);
  EXPECT_NEAR(sweep[10].norm(), 0.0, 1e-15);
  EXPECT_NEAR(sweep.front().x(), -0.05, 1e-15);
  EXPECT_NEAR(sweep.back().x(), 0.05, 1e-15);
  for (size_t i = 1; i < sweep.size(); ++i) {
    EXPECT_LE((sweep[i] - sweep[i - 1]).norm(), options.cartesian_step_m + 1e-12);
  }
}

TEST(StrokeWaypoints, SecateurApproachesClosesAndRetracts) {
  CutMotionOptions options;
  int cut_index = -1;
  const auto stroke = StrokeWaypoints(CutStroke::kApproachCloseRetract, options, &cut_index);
  ASSERT_EQ(stroke.size(), 25u);
  EXPECT_EQ(cut_index, 12);
  EXPECT_NEAR(stroke.front().z(), -0.06, 1e-15);
  EXPECT_NEAR(stroke[12].norm(), 0.0, 1e-15);
  EXPECT_EQ(stroke.front(), stroke.back());
}

TEST(SampleCutPoses, FramesCrossTheCaneAndTiltAboutTheSweepAxis) {
  CutMotionOptions options;
  options.max_tilt_rad = 0.4;
  options.tilt_steps = 2;
  const Eigen::Vector3d p(0.4, 0.1, 0.3), d = Eigen::Vector3d(0.2, -0.1, 1).normalized();
  const auto poses = SampleCutPoses(p, d, options);
  ASSERT_EQ(poses.size(), 16u * 2u * 5u);
  double max_tilt = 0;
  for (const Eigen::Isometry3d& pose : poses) {
    const Eigen::Matrix3d r = pose.linear();
    EXPECT_TRUE((r.transpose() * r).isIdentity(1e-12));
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
    EXPECT_EQ(pose.translation(), p);
    EXPECT_NEAR(r.col(0).dot(d), 0.0, 1e-12);  // the sweep is always across the cane
    max_tilt = std::max(max_tilt, std::asin(std::min(1.0, std::abs(r.col(2).dot(d)))));
  }
  EXPECT_NEAR(max_tilt, 0.4, 1e-9);
  // The first samples are perpendicular, theta = 0 pointing from the base toward the cane.
  EXPECT_NEAR(poses[0].linear().col(2).dot(d), 0.0, 1e-12);
  EXPECT_GT(poses[0].linear().col(2).dot(p), 0.0);
}

TEST(SampleCutPoses, RollsTurnTheJawsAboutTheToolAxisAfterTheUnrolledPoses) {
  CutMotionOptions options;
  options.max_tilt_rad = 0.3;
  options.tilt_steps = 1;
  options.max_roll_rad = 0.6;
  options.roll_steps = 2;
  const Eigen::Vector3d p(0.4, 0.1, 0.3), d = Eigen::Vector3d(0.2, -0.1, 1).normalized();
  const auto poses = SampleCutPoses(p, d, options);
  const size_t unrolled = 16u * 2u * 3u;
  ASSERT_EQ(poses.size(), unrolled * 5u);
  double max_roll = 0, max_tilt = 0;
  bool half_step = false;
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Matrix3d r = poses[i].linear();
    EXPECT_TRUE((r.transpose() * r).isIdentity(1e-12));
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
    EXPECT_EQ(poses[i].translation(), p);
    // The tilt moves the cane out of the tool's cross-section, the roll turns it within it:
    // x . d = sin(roll) cos(tilt) (up to sign), z . d = sin(tilt).
    const double tilt = std::asin(std::min(1.0, std::abs(r.col(2).dot(d))));
    const double roll = std::asin(std::min(1.0, std::abs(r.col(0).dot(d)) / std::cos(tilt)));
    max_tilt = std::max(max_tilt, tilt);
    max_roll = std::max(max_roll, roll);
    if (i < unrolled) EXPECT_NEAR(roll, 0.0, 1e-9) << i;  // unrolled poses come first
    else EXPECT_GT(roll, 0.29) << i;
    half_step = half_step || std::abs(roll - 0.3) < 1e-9;
  }
  EXPECT_NEAR(max_tilt, 0.3, 1e-9);
  EXPECT_NEAR(max_roll, 0.6, 1e-9);
  EXPECT_TRUE(half_step);
}

TEST(SampleCutPoses, EachOtherSidePoseIsAFirstSidePoseRolledByPi) {
  // Sides alternate; the other side's pose at tilt +t is the first side's at tilt -t (same
  // orientation and roll) with x and y reversed, bit for bit: cut_motion.cc samples one side only
  // and takes the other's motions as half-turn twins.
  CutMotionOptions options;
  options.max_tilt_rad = 0.4;
  options.tilt_steps = 2;
  options.max_roll_rad = 0.6;
  options.roll_steps = 2;
  const Eigen::Vector3d p(0.4, 0.1, 0.3), d = Eigen::Vector3d(0.2, -0.1, 1).normalized();
  const auto poses = SampleCutPoses(p, d, options);
  ASSERT_EQ(poses.size(), 16u * 2u * 5u * 5u);
  std::vector<int> twin_of(poses.size(), -1);
  for (size_t i = 1; i < poses.size(); i += 2) {
    for (size_t j = 0; j < poses.size(); j += 2) {
      const Eigen::Matrix3d& a = poses[i].linear();
      const Eigen::Matrix3d& b = poses[j].linear();
      if (a.col(0) == -b.col(0) && a.col(1) == -b.col(1) && a.col(2) == b.col(2) &&
          poses[i].translation() == poses[j].translation()) {
        EXPECT_EQ(twin_of[j], -1) << "two poses roll onto pose " << j;
        twin_of[j] = static_cast<int>(i);
      }
    }
  }
  for (size_t j = 0; j < poses.size(); j += 2) EXPECT_GE(twin_of[j], 0) << j;
  // With tilts, a twin is not its neighbour: the pairing is by geometry, not by index.
  EXPECT_NE(twin_of[2 * 16 * 2], 2 * 16 * 2 + 1);
}

TEST(CutMotionOptions, ValidateRejectsBadRolls) {
  CutMotionOptions bad;
  bad.roll_steps = -1;
  EXPECT_THAT(bad.Validate().message(), HasSubstr("options.roll_steps"));
  bad = CutMotionOptions();
  bad.max_roll_rad = 2.0;
  EXPECT_THAT(bad.Validate().message(), HasSubstr("options.max_roll_rad"));
  bad.max_roll_rad = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(bad.Validate().message(), HasSubstr("options.max_roll_rad"));
}

// A half ring of 3 mm balls 30 mm from the cut cane's axis in the plane of the cut, on the far
// side from the arm: an unrolled secateur's jaws (their axes 23.5 mm from the cane, reaching
// 45 mm past it) cross that circle in every orientation; rolled by 45 degrees about its axis
// they pass 16.6 mm above and below the plane.
std::vector<Obstacle> HalfRingAroundTheCut() {
  std::vector<Obstacle> ring;
  for (int k = -6; k <= 6; ++k) {
    const double a = k * M_PI / 12;
    ring.push_back(Ball({0.05 + 0.03 * std::sin(a), 0.8 + 0.03 * std::cos(a), 0.95}, 0.003));
  }
  return ring;
}

TEST(CutMotion, SecateurRollsAboutItsAxisWhereNoSquareCutIsFree) {
  const RobotModel robot = TestRobot(SecateurTool());
  const TestWorld w = MakeWorld(robot, HalfRingAroundTheCut());
  CutMotionOptions options;
  options.max_slide_m = 0;
  const auto square = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                                     Deadline::Infinite(), MakeBruteForce);
  EXPECT_EQ(square[0].outcome, CutMotionOutcome::kNoCollisionFreeMotion) << square[0].message;
  options.max_roll_rad = M_PI / 4;
  options.roll_steps = 2;
  const auto rolled = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                                     Deadline::Infinite(), MakeBruteForce);
  const CutMotion& m = rolled[0];
  ASSERT_EQ(m.outcome, CutMotionOutcome::kPlanned) << m.message;
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  const Eigen::Vector3d cane_in_base = base_from_platform.linear() * w.cut.direction;
  const Eigen::Isometry3d at_cut = TcpInBase(robot, m.path[m.cut_index]);
  EXPECT_LT((at_cut.translation() - base_from_platform * w.cut.point).norm(), 1e-9);
  EXPECT_NEAR(at_cut.linear().col(2).dot(cane_in_base), 0.0, 1e-9);  // no tilt was needed
  EXPECT_GT(std::abs(at_cut.linear().col(0).dot(cane_in_base)), 0.5);  // rolled
  // Nothing touches, not even the cut cane: it passes between the open jaws.
  BruteForceChecker full(robot, w.scene);
  for (const Joints& q : m.path) EXPECT_TRUE(full.IsFree(q));
}

TEST(CutMotion, SecateurJawsNeverTouchTheCutCane) {
  const RobotModel robot = TestRobot(SecateurTool());
  TestWorld w = MakeWorld(robot);
  CutMotionOptions options;
  options.max_roll_rad = M_PI / 4;
  options.roll_steps = 2;
  const auto thin = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                                   Deadline::Infinite(), MakeBruteForce);
  ASSERT_EQ(thin[0].outcome, CutMotionOutcome::kPlanned) << thin[0].message;
  BruteForceChecker full(robot, w.scene);
  for (const Joints& q : thin[0].path) EXPECT_TRUE(full.IsFree(q));
  // A cane 38 mm thick does not fit between jaws open 35 mm: no motion, though the cut cane near
  // the cut is not an obstacle for the arm.
  for (Obstacle& o : w.scene.obstacles)
    if (o.owner_id == kCutCane) o.capsule.radius = 0.019;
  const auto thick = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                                    Deadline::Infinite(), MakeBruteForce);
  EXPECT_EQ(thick[0].outcome, CutMotionOutcome::kNoCollisionFreeMotion) << thick[0].message;
  // The mill end cuts through it.
  const RobotModel mill = TestRobot(MillEndTool());
  TestWorld mill_world = MakeWorld(mill);
  for (Obstacle& o : mill_world.scene.obstacles)
    if (o.owner_id == kCutCane) o.capsule.radius = 0.019;
  EXPECT_EQ(PlanCutMotions(mill, mill_world.model, mill_world.scene, std::span(&mill_world.cut, 1),
                           options, Deadline::Infinite(), MakeBruteForce)[0]
                .outcome,
            CutMotionOutcome::kPlanned);
}

TEST(CutMotion, MinimumClearanceRejectsMotionsThatGraze) {
  const RobotModel robot = TestRobot(SecateurTool());
  const TestWorld w = MakeWorld(robot);
  CutMotionOptions options;
  options.max_slide_m = 0;
  const auto best = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                                   Deadline::Infinite(), MakeBruteForce);
  ASSERT_EQ(best[0].outcome, CutMotionOutcome::kPlanned) << best[0].message;
  options.min_clearance_m = 0.5 * best[0].clearance_m;
  const auto half = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                                   Deadline::Infinite(), MakeBruteForce);
  ASSERT_EQ(half[0].outcome, CutMotionOutcome::kPlanned) << half[0].message;
  EXPECT_EQ(half[0].clearance_m, best[0].clearance_m);
  options.min_clearance_m = best[0].clearance_m + 1e-4;  // the best has too little
  EXPECT_EQ(PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                           Deadline::Infinite(), MakeBruteForce)[0]
                .outcome,
            CutMotionOutcome::kNoCollisionFreeMotion);
  options.min_clearance_m = -1;
  EXPECT_THAT(options.Validate().message(), HasSubstr("options.min_clearance_m"));
}

TEST(CutMotion, TiltedCutStillSweepsAcrossTheCaneThroughTheCut) {
  const RobotModel robot = TestRobot(MillEndTool());
  // A wide ball 12 mm below the cut: a perpendicular (horizontal) tool's body, 33 mm in radius,
  // dips into it in every orientation; a tool tilted up clears it.
  const TestWorld w = MakeWorld(robot, {Ball({0.05, 0.8, 0.95 - 0.012 - 0.3}, 0.3)});
  CutMotionOptions options;
  options.max_slide_m = 0;
  options.max_tilt_rad = 0.6;
  options.tilt_steps = 2;
  const auto motions = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                                      Deadline::Infinite(), MakeBruteForce);
  const CutMotion& m = motions[0];
  ASSERT_EQ(m.outcome, CutMotionOutcome::kPlanned) << m.message;
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  const Eigen::Isometry3d at_cut = TcpInBase(robot, m.path[m.cut_index]);
  const Eigen::Vector3d cane_in_base = base_from_platform.linear() * w.cut.direction;
  EXPECT_LT((at_cut.translation() - base_from_platform * w.cut.point).norm(), 1e-9);
  EXPECT_NEAR(at_cut.linear().col(0).dot(cane_in_base), 0.0, 1e-9);
  EXPECT_GT(std::abs(at_cut.linear().col(2).dot(cane_in_base)), 0.1);  // it did tilt
  options.tilt_steps = 0;
  EXPECT_EQ(PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                           Deadline::Infinite(), MakeBruteForce)[0]
                .outcome,
            CutMotionOutcome::kNoCollisionFreeMotion);
}

TEST(CutMotion, MillEndSweepsThroughTheCutPerpendicularToTheCane) {
  const RobotModel robot = TestRobot(MillEndTool());
  const TestWorld w = MakeWorld(robot);
  const CutMotionOptions options;
  const auto motions = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                                      Deadline::Infinite(), MakeBruteForce);
  ASSERT_EQ(motions.size(), 1u);
  const CutMotion& m = motions[0];
  ASSERT_EQ(m.outcome, CutMotionOutcome::kPlanned) << m.message;
  EXPECT_EQ(m.cut_id, CutId(1));
  EXPECT_EQ(m.slid_m, 0.0);
  ASSERT_EQ(m.path.size(), 21u);
  ASSERT_EQ(m.cut_index, 10);
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  const Eigen::Vector3d cut_in_base = base_from_platform * w.cut.point;
  const Eigen::Vector3d cane_in_base = base_from_platform.linear() * w.cut.direction;
  const Eigen::Isometry3d at_cut = TcpInBase(robot, m.path[m.cut_index]);
  EXPECT_LT((at_cut.translation() - cut_in_base).norm(), 1e-9);
  EXPECT_NEAR(std::abs(at_cut.linear().col(1).dot(cane_in_base)), 1.0, 1e-9);  // cane along y
  EXPECT_NEAR(at_cut.linear().col(2).dot(cane_in_base), 0.0, 1e-9);            // z across it
  // Every configuration keeps the orientation and lies on the sweep line, ends 0.05 m out.
  const Eigen::Vector3d sweep_axis = at_cut.linear().col(0);
  for (size_t i = 0; i < m.path.size(); ++i) {
    const Eigen::Isometry3d tcp = TcpInBase(robot, m.path[i]);
    EXPECT_LT((tcp.linear() - at_cut.linear()).norm(), 1e-9) << i;
    const Eigen::Vector3d offset = tcp.translation() - cut_in_base;
    EXPECT_LT((offset - offset.dot(sweep_axis) * sweep_axis).norm(), 1e-9) << i;
    EXPECT_NEAR(offset.dot(sweep_axis), -0.05 + 0.005 * i, 1e-9) << i;
    EXPECT_TRUE(robot.limits.Contains(m.path[i]));
    if (i > 0) {
      EXPECT_LE((m.path[i] - m.path[i - 1]).cwiseAbs().maxCoeff(), options.max_joint_jump_rad);
    }
  }
}

TEST(CutMotion, PathIsFreeOfEverythingButTheCutCaneNearTheCut) {
  const RobotModel robot = TestRobot(MillEndTool());
  const TestWorld w = MakeWorld(robot);
  const CutMotionOptions options;
  const auto motions = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                                      Deadline::Infinite(), MakeBruteForce);
  ASSERT_EQ(motions[0].outcome, CutMotionOutcome::kPlanned) << motions[0].message;
  // The scene minus the cut cane's segments near the cut, filtered here independently.
  const Eigen::Vector3d cut_in_base = robot.platform_from_arm_base.inverse() * w.cut.point;
  CollisionScene allowed = w.scene;
  std::erase_if(allowed.obstacles, [&](const Obstacle& o) {
    return o.owner_id == kCutCane && PointSegmentDistance(cut_in_base, o.capsule.a, o.capsule.b) <
                                         options.cut_cane_free_radius_m;
  });
  ASSERT_LT(allowed.obstacles.size(), w.scene.obstacles.size());
  BruteForceChecker allowed_checker(robot, allowed), full_checker(robot, w.scene);
  double clearance = std::numeric_limits<double>::infinity();
  for (const Joints& q : motions[0].path) {
    EXPECT_GT(allowed_checker.Clearance(q), 0.0);
    clearance = std::min(clearance, allowed_checker.Clearance(q));
  }
  EXPECT_NEAR(motions[0].clearance_m, clearance, 1e-12);
  // The tool does go through the cane: at the cut the full scene is in contact, at both ends not.
  EXPECT_FALSE(full_checker.IsFree(motions[0].path[motions[0].cut_index]));
  EXPECT_TRUE(full_checker.IsFree(motions[0].path.front()));
  EXPECT_TRUE(full_checker.IsFree(motions[0].path.back()));
}

TEST(CutMotion, SecateurApproachesAlongItsAxisAndRetracts) {
  const RobotModel robot = TestRobot(SecateurTool());
  const TestWorld w = MakeWorld(robot);
  const auto motions = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1),
                                      CutMotionOptions(), Deadline::Infinite(), MakeBruteForce);
  const CutMotion& m = motions[0];
  ASSERT_EQ(m.outcome, CutMotionOutcome::kPlanned) << m.message;
  ASSERT_EQ(m.path.size(), 25u);
  const Eigen::Vector3d cut_in_base = robot.platform_from_arm_base.inverse() * w.cut.point;
  const Eigen::Isometry3d at_cut = TcpInBase(robot, m.path[m.cut_index]);
  EXPECT_LT((at_cut.translation() - cut_in_base).norm(), 1e-9);
  const Eigen::Isometry3d start = TcpInBase(robot, m.path.front());
  EXPECT_LT((start.translation() - (cut_in_base - 0.06 * at_cut.linear().col(2))).norm(), 1e-9);
  EXPECT_LT((m.path.front() - m.path.back()).norm(), 1e-9);  // retracts the way it came
}

TEST(CutMotion, CutOutOfReachIsUnreachable) {
  const RobotModel robot = TestRobot(MillEndTool());
  TestWorld w = MakeWorld(robot);
  Cane far = w.model.canes[0];
  for (Eigen::Vector3d& p : far.polyline.points) p.x() += 2.0;
  w.model.canes[0] = far;
  w.cut.point.x() += 2.0;
  const auto motions = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1),
                                      CutMotionOptions(), Deadline::Infinite(), MakeBruteForce);
  EXPECT_EQ(motions[0].outcome, CutMotionOutcome::kUnreachable) << motions[0].message;
  EXPECT_TRUE(motions[0].path.empty());
}

TEST(CutMotion, CutInsideAnObstacleHasNoCollisionFreeMotion) {
  const RobotModel robot = TestRobot(MillEndTool());
  const TestWorld w = MakeWorld(robot, {Ball({0.05, 0.8, 0.95}, 0.2)});
  const auto motions = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1),
                                      CutMotionOptions(), Deadline::Infinite(), MakeBruteForce);
  EXPECT_EQ(motions[0].outcome, CutMotionOutcome::kNoCollisionFreeMotion) << motions[0].message;
}

TEST(CutMotion, CutAtAnObstacleSlidesOutwardAlongTheCane) {
  const RobotModel robot = TestRobot(MillEndTool());
  // A head-like ball whose surface passes through the cut point, below it on the cane.
  const TestWorld w = MakeWorld(robot, {Ball({0.05, 0.8, 0.85}, 0.1)});
  const CutMotionOptions options;
  const auto motions = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), options,
                                      Deadline::Infinite(), MakeBruteForce);
  const CutMotion& m = motions[0];
  ASSERT_EQ(m.outcome, CutMotionOutcome::kPlanned) << m.message;
  EXPECT_GT(m.slid_m, 0.0);
  EXPECT_LE(m.slid_m, options.max_slide_m);
  EXPECT_NEAR(m.cut_point_in_platform.z(), 0.95 + m.slid_m, 1e-9);  // toward the tip (up)
  const Eigen::Vector3d cut_in_base =
      robot.platform_from_arm_base.inverse() * m.cut_point_in_platform;
  EXPECT_LT((TcpInBase(robot, m.path[m.cut_index]).translation() - cut_in_base).norm(), 1e-9);
  // Without sliding the same cut has no motion.
  CutMotionOptions no_slide = options;
  no_slide.max_slide_m = 0;
  EXPECT_EQ(PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1), no_slide,
                           Deadline::Infinite(), MakeBruteForce)[0]
                .outcome,
            CutMotionOutcome::kNoCollisionFreeMotion);
}

TEST(CutMotion, SlideStopsShortOfTheBaseOfAChildBeyondTheCut) {
  const RobotModel robot = TestRobot(MillEndTool());
  TestWorld w = MakeWorld(robot, {Ball({0.05, 0.8, 0.85}, 0.1)});
  const CutMotionOptions options;
  const CutMotion free_slide = PlanCutMotions(robot, w.model, w.scene, std::span(&w.cut, 1),
                                              options, Deadline::Infinite(), MakeBruteForce)[0];
  ASSERT_EQ(free_slide.outcome, CutMotionOutcome::kPlanned) << free_slide.message;
  ASSERT_GT(free_slide.slid_m, 0.0);
  // A child of the cut cane: in the model only (the scene, which the checks use, is unchanged).
  auto add_child = [](TestWorld world, double base_z) {
    Cane child;
    child.id = CaneId(7);
    child.parent_id = CaneId(kCutCane);
    child.polyline.points = {{0.05, 0.8, base_z}, {0.05, 0.9, base_z + 0.1}};
    child.polyline.radii = {0.004, 0.004};
    world.model.canes.push_back(child);
    return world;
  };
  // Its base between the given cut and the first free slide: the cut would leave it on the vine.
  const TestWorld blocked = add_child(w, 0.95 + free_slide.slid_m - 0.5 * options.slide_step_m);
  const CutMotion stopped = PlanCutMotions(robot, blocked.model, blocked.scene,
                                           std::span(&blocked.cut, 1), options,
                                           Deadline::Infinite(), MakeBruteForce)[0];
  EXPECT_EQ(stopped.outcome, CutMotionOutcome::kNoCollisionFreeMotion) << stopped.message;
  // Its base below the cut (it stays anyway) or beyond the slide: the same motion as without.
  for (double base_z : {0.90, 0.95 + free_slide.slid_m + 0.5 * options.slide_step_m}) {
    const TestWorld other = add_child(w, base_z);
    const CutMotion m = PlanCutMotions(robot, other.model, other.scene, std::span(&other.cut, 1),
                                       options, Deadline::Infinite(), MakeBruteForce)[0];
    ASSERT_EQ(m.outcome, CutMotionOutcome::kPlanned) << "child at z " << base_z;
    EXPECT_EQ(m.slid_m, free_slide.slid_m) << "child at z " << base_z;
    EXPECT_EQ(m.path, free_slide.path) << "child at z " << base_z;
  }
}

TEST(CutMotion, BadInputGivesInvalidInputPerCut) {
  const RobotModel robot = TestRobot(MillEndTool());
  const TestWorld w = MakeWorld(robot);
  std::vector<Cut> cuts(3, w.cut);
  cuts[0].point.y() = std::numeric_limits<double>::quiet_NaN();
  cuts[1].cane_id = CaneId(99);
  cuts[2].id = CutId(3);
  auto motions = PlanCutMotions(robot, w.model, w.scene, cuts, CutMotionOptions(),
                                Deadline::Infinite(), MakeBruteForce);
  ASSERT_EQ(motions.size(), 3u);
  EXPECT_EQ(motions[0].outcome, CutMotionOutcome::kInvalidInput);
  EXPECT_EQ(motions[1].outcome, CutMotionOutcome::kInvalidInput);
  EXPECT_THAT(motions[1].message, HasSubstr("cane 99"));
  EXPECT_EQ(motions[2].outcome, CutMotionOutcome::kPlanned);
  CutMotionOptions bad;
  bad.sweep_m = -1;
  EXPECT_THAT(bad.Validate().message(), HasSubstr("options.sweep_m"));
  motions =
      PlanCutMotions(robot, w.model, w.scene, cuts, bad, Deadline::Infinite(), MakeBruteForce);
  for (const CutMotion& m : motions) {
    EXPECT_EQ(m.outcome, CutMotionOutcome::kInvalidInput);
    EXPECT_THAT(m.message, HasSubstr("options.sweep_m"));
  }
  bad = CutMotionOptions();
  bad.approach_sides = 3;
  EXPECT_THAT(bad.Validate().message(), HasSubstr("options.approach_sides"));
  bad = CutMotionOptions();
  bad.slide_step_m = 0;
  EXPECT_THAT(bad.Validate().message(), HasSubstr("options.slide_step_m"));
}

TEST(CutMotion, ExpiredDeadlineReportsEveryCut) {
  const RobotModel robot = TestRobot(MillEndTool());
  const TestWorld w = MakeWorld(robot);
  std::atomic<bool> cancelled{true};
  std::vector<Cut> cuts(2, w.cut);
  const auto motions = PlanCutMotions(robot, w.model, w.scene, cuts, CutMotionOptions(),
                                      Deadline::In(10.0, &cancelled), MakeBruteForce);
  ASSERT_EQ(motions.size(), 2u);
  for (const CutMotion& m : motions) EXPECT_EQ(m.outcome, CutMotionOutcome::kDeadline);
}

}  // namespace
}  // namespace vb::plan
