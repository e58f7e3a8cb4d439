// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/collision_checker.h"

#include <cmath>
#include <random>

#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/plan/fcl_checker.h"
#include "workers/plan/primitive_checker.h"
#include "workers/plan/simple_tool_test_util.h"
#include "workers/plan/tool.h"

namespace vb::plan {
namespace {

CollisionScene VineScene(uint64_t seed, double margin_m = 0.0) {
  sim::VineGeneratorOptions options;
  options.neighbours = false;
  auto sim_scene = sim::GenerateScene(seed, 0, options);
  EXPECT_TRUE(sim_scene.ok()) << sim_scene.status();
  SceneOptions scene_options;
  scene_options.default_margin_m = margin_m;
  auto scene = CollisionScene::Build(sim_scene->vine, DefaultPlatform(), DefaultUr5(SimpleMillEnd()),
                                     scene_options);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return *scene;
}

Joints RandomJoints(std::mt19937& rng, const JointLimits& limits) {
  Joints q;
  for (int i = 0; i < 6; ++i) {
    q[i] = std::uniform_real_distribution<double>(limits.lower[i], limits.upper[i])(rng);
  }
  return q;
}

// Independent reference: LinkFrames and core's segment distances over every pair, brute force.
double ReferenceClearance(const RobotModel& robot, const CollisionScene& scene, const Joints& q) {
  const auto f = LinkFrames(q);
  const auto bodies = robot.BodiesWithTool();
  double best = 1e9;
  auto gap = [](const Capsule& x, const Capsule& y, double extra) {
    return SegmentSegmentDistance(x.a, x.b, y.a, y.b) - x.radius - y.radius - extra;
  };
  std::vector<std::vector<Capsule>> world(bodies.size());
  for (size_t b = 0; b < bodies.size(); ++b) {
    for (const Capsule& c : bodies[b].capsules) {
      world[b].push_back({f[bodies[b].frame] * c.a, f[bodies[b].frame] * c.b, c.radius});
    }
  }
  for (const auto& caps : world) {
    for (const Capsule& c : caps) {
      for (const Obstacle& o : scene.obstacles) best = std::min(best, gap(c, o.capsule, o.margin_m));
      for (const HalfSpace& h : scene.planes) {
        best = std::min(best, h.offset - std::max(h.normal.dot(c.a), h.normal.dot(c.b)) -
                                  c.radius - h.margin_m);
      }
    }
  }
  for (const auto& [i, j] : robot.SelfCollisionPairs()) {
    for (const Capsule& x : world[i]) {
      for (const Capsule& y : world[j]) best = std::min(best, gap(x, y, 0.0));
    }
  }
  return best;
}

// A configuration with the arm raised clear of everything in an empty scene.
Joints Raised() {
  Joints q;
  q << 0.0, -1.57, 0.3, -1.0, -1.57, 0.0;
  return q;
}

CollisionScene EmptyScene() { return CollisionScene(); }

TEST(PrimitiveChecker, ClearanceMatchesBruteForceOnVines) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  std::mt19937 rng(1104);
  for (uint64_t seed : {1104, 1105}) {
    const CollisionScene scene = VineScene(seed, 0.01);
    PrimitiveChecker checker(robot, scene);
    EXPECT_GT(checker.pieces(), 200);
    for (int trial = 0; trial < 200; ++trial) {
      const Joints q = RandomJoints(rng, robot.limits);
      const double expected = ReferenceClearance(robot, scene, q);
      const double clearance = checker.Clearance(q);
      ASSERT_NEAR(clearance, expected, 1e-9) << "seed " << seed << " trial " << trial;
      if (std::abs(expected) > 2e-5) {
        ASSERT_EQ(checker.IsFree(q), expected > 0) << "seed " << seed << " trial " << trial;
      }
    }
  }
}

// ClearanceAbove: bit for bit min(cap, Clearance) when that beats the floor, else <= floor;
// the base class's default agrees.
TEST(PrimitiveChecker, ClearanceAboveIsTheCappedClearanceOrBelowTheFloor) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  std::mt19937 rng(1106);
  const CollisionScene scene = VineScene(1106, 0.01);
  PrimitiveChecker checker(robot, scene);
  int above = 0, below = 0, capped = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Joints q = RandomJoints(rng, robot.limits);
    const double exact = checker.Clearance(q);
    // Floors and caps about the clearance, so that every branch is taken.
    const double floor = exact + std::uniform_real_distribution<double>(-0.05, 0.02)(rng);
    const double cap = exact + std::uniform_real_distribution<double>(-0.02, 0.05)(rng);
    const double got = checker.ClearanceAbove(q, floor, cap);
    const double want = std::min(cap, exact);
    if (want > floor) {
      ASSERT_EQ(got, want) << "trial " << trial;
      ++above;
      capped += cap < exact;
    } else {
      ASSERT_LE(got, floor) << "trial " << trial;
      ++below;
    }
    ASSERT_EQ(checker.CollisionChecker::ClearanceAbove(q, floor, cap) > floor, want > floor);
  }
  EXPECT_GT(above, 20);
  EXPECT_GT(below, 20);
  EXPECT_GT(capped, 5);
}

TEST(PrimitiveChecker, FoldedArmCollidesWithItself) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  const CollisionScene scene = EmptyScene();
  PrimitiveChecker checker(robot, scene);
  EXPECT_TRUE(checker.IsFree(Raised()));
  EXPECT_GT(checker.Clearance(Raised()), 0.0);
  Joints folded = Raised();
  folded[2] = 3.0;  // the wrist comes back onto the shoulder
  EXPECT_FALSE(checker.IsFree(folded));
  EXPECT_LT(checker.Clearance(folded), 0.0);
  EXPECT_EQ(checker.checks(), 4);
  for (FclMode mode : {FclMode::kPrimitives, FclMode::kMesh}) {
    auto fcl = MakeFclChecker(robot, scene, mode);
    EXPECT_TRUE(fcl->IsFree(Raised()));
    EXPECT_FALSE(fcl->IsFree(folded));
  }
}

TEST(PrimitiveChecker, GroundPlaneStopsTheArm) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  auto with_planes = CollisionScene::Build(VineModel(), DefaultPlatform(), robot);
  ASSERT_TRUE(with_planes.ok());
  // Reach straight down: the flange ends ~0.9 m below the base, beyond the ground at -0.55 m.
  Joints down;
  down << 0.0, M_PI / 2, 0.0, 0.0, 0.0, 0.0;
  if (ForwardKinematics(down).translation().z() > -0.6) down[1] = -M_PI / 2;
  ASSERT_LT(ForwardKinematics(down).translation().z(), -0.6);
  PrimitiveChecker checker(robot, *with_planes);
  EXPECT_FALSE(checker.IsFree(down));
  CollisionScene no_planes = *with_planes;
  no_planes.planes.clear();
  no_planes.obstacles.clear();
  PrimitiveChecker free_checker(robot, no_planes);
  EXPECT_TRUE(free_checker.IsFree(down));
  EXPECT_FALSE(MakeFclChecker(robot, *with_planes, FclMode::kPrimitives)->IsFree(down));
  EXPECT_FALSE(MakeFclChecker(robot, *with_planes, FclMode::kMesh)->IsFree(down));
}

TEST(PrimitiveChecker, MarginsInflateObstacles) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  const double arm_only = PrimitiveChecker(robot, EmptyScene()).Clearance(Raised());
  ASSERT_GT(arm_only, 0.006);
  // A 5 mm sphere 5 mm beyond the tool tip.
  const Eigen::Isometry3d flange = ForwardKinematics(Raised());
  const Eigen::Vector3d tip = flange * Eigen::Vector3d(0, 0, 0.17 + 0.006);
  CollisionScene scene;
  Obstacle sphere;
  sphere.kind = ObstacleKind::kHead;
  sphere.capsule = {tip + 0.01 * flange.linear().col(2), tip + 0.01 * flange.linear().col(2),
                    0.005};
  scene.obstacles.push_back(sphere);
  {
    PrimitiveChecker checker(robot, scene);
    EXPECT_TRUE(checker.IsFree(Raised()));
    EXPECT_NEAR(checker.Clearance(Raised()), 0.005, 1e-9);
  }
  scene.obstacles[0].margin_m = 0.01;
  PrimitiveChecker checker(robot, scene);
  EXPECT_FALSE(checker.IsFree(Raised()));
  EXPECT_NEAR(checker.Clearance(Raised()), -0.005, 1e-9);
  for (FclMode mode : {FclMode::kPrimitives, FclMode::kMesh}) {
    EXPECT_FALSE(MakeFclChecker(robot, scene, mode)->IsFree(Raised()));
  }
}

TEST(PrimitiveChecker, LongObstaclesAreSplitWithoutChangingThem) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  // A 0.8 m post (7 pieces) past the tool tip, 0.02 m beside it.
  const Eigen::Isometry3d flange = ForwardKinematics(Raised());
  const Eigen::Vector3d tip = flange * Eigen::Vector3d(0, 0, 0.17);
  const Eigen::Vector3d side = flange.linear().col(1);
  const Eigen::Vector3d along = flange.linear().col(0);
  CollisionScene scene;
  Obstacle post;
  post.kind = ObstacleKind::kPost;
  post.capsule = {tip + (0.006 + 0.02 + 0.04) * side - 0.4 * along,
                  tip + (0.006 + 0.02 + 0.04) * side + 0.4 * along, 0.04};
  scene.obstacles.push_back(post);
  PrimitiveChecker checker(robot, scene);
  EXPECT_EQ(checker.pieces(), 7);
  EXPECT_NEAR(checker.Clearance(Raised()), ReferenceClearance(robot, scene, Raised()), 1e-9);
  EXPECT_TRUE(checker.IsFree(Raised())) << checker.Clearance(Raised());
  scene.obstacles[0].margin_m = 0.03;
  EXPECT_FALSE(PrimitiveChecker(robot, scene).IsFree(Raised()));
}

TEST(PrimitiveChecker, BaseInsideAnObstacleIsNeverFree) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  CollisionScene scene;
  Obstacle o;
  o.capsule = {Eigen::Vector3d(0.05, 0, 0.02), Eigen::Vector3d(0.05, 0, 0.02), 0.02};
  scene.obstacles.push_back(o);
  PrimitiveChecker checker(robot, scene);
  EXPECT_FALSE(checker.IsFree(Raised()));
  EXPECT_LT(checker.Clearance(Raised()), 0.0);
}

TEST(PrimitiveChecker, NonFiniteConfigurationIsNeverFree) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  PrimitiveChecker checker(robot, EmptyScene());
  Joints q = Raised();
  q[3] = std::nan("");
  EXPECT_FALSE(checker.IsFree(q));
  EXPECT_LT(checker.Clearance(q), 0.0);
  // Angles beyond a turn wrap around exactly.
  Joints wrapped = Raised();
  wrapped[0] += 4 * M_PI;
  wrapped[5] -= 6 * M_PI;
  EXPECT_NEAR(checker.Clearance(wrapped), checker.Clearance(Raised()), 1e-12);
}

TEST(MotionSteps, BoundsTheTravelOfEveryPoint) {
  Joints a = Joints::Zero(), b = Joints::Zero();
  EXPECT_EQ(MotionSteps(a, b, 0.01), 1);
  b[0] = 1.0;
  b[3] = -0.5;
  const int n = MotionSteps(a, b, 0.01, 1.0);
  EXPECT_EQ(n, 150);
  EXPECT_GE(MotionSteps(a, b, 0.001, 1.0), 10 * n - 1);
  EXPECT_GT(MotionSteps(a, b, 0.0), 1000);  // a bad step never gives a coarse check
  b[1] = std::nan("");
  EXPECT_GT(MotionSteps(a, b, 0.01), 1000);
}

// The largest travel of any capsule point between two configurations: an endpoint's displacement
// plus the radius times the chord of the body's rotation (|(R' - R) u| = 2 sin(angle / 2)).
double MaxCapsuleTravel(const std::vector<LinkBody>& bodies, const Joints& q0, const Joints& q1) {
  const auto f0 = LinkFrames(q0), f1 = LinkFrames(q1);
  double worst = 0;
  for (const LinkBody& body : bodies) {
    const Eigen::Matrix3d r = f0[body.frame].linear().transpose() * f1[body.frame].linear();
    const double angle = Eigen::AngleAxisd(r).angle();
    for (const Capsule& c : body.capsules) {
      for (const Eigen::Vector3d& e : {c.a, c.b}) {
        worst = std::max(worst, (f1[body.frame] * e - f0[body.frame] * e).norm() +
                                    c.radius * 2 * std::sin(angle / 2));
      }
    }
  }
  return worst;
}

TEST(JointLeverArms, BoundTheTravelOfEveryCapsulePointPerStep) {
  for (const ToolGeometry& tool : {SimpleMillEnd(), MillEndTool(), SecateurTool()}) {
    const RobotModel robot = DefaultUr5(tool);
    const std::vector<LinkBody> bodies = robot.BodiesWithTool();
    const JointLevers lever = JointLeverArms(robot);
    std::mt19937 rng(1120);
    double tightest = 0;
    for (int trial = 0; trial < 1200; ++trial) {
      const Joints a = RandomJoints(rng, robot.limits);
      Joints b = RandomJoints(rng, robot.limits);
      // Short motions too, and motions of one joint (where one lever alone is tested).
      if (trial % 3 == 1) b = a + (b - a) * 0.05;
      if (trial % 3 == 2) {
        const int i = trial % 6;
        b = a;
        b[i] = a[i] + std::uniform_real_distribution<double>(-0.5, 0.5)(rng);
      }
      constexpr double kStep = 0.01;
      const int n = MotionSteps(a, b, kStep, lever);
      for (int k = 0; k < n; ++k) {
        const double travel =
            MaxCapsuleTravel(bodies, a + (b - a) * (double(k) / n), a + (b - a) * (double(k + 1) / n));
        ASSERT_LE(travel, kStep * (1 + 1e-9)) << tool.name << " trial " << trial << " step " << k;
        tightest = std::max(tightest, travel / kStep);
      }
    }
    // The bound is useful, not only safe: single-joint steps come close to it.
    EXPECT_GT(tightest, 0.8) << tool.name;
  }
}

TEST(JointLeverArms, WristJointsMoveLessThanTheShoulder) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  const JointLevers lever = JointLeverArms(robot);
  for (int i = 0; i < 6; ++i) {
    EXPECT_GT(lever[i], 0.0) << i;
    RecordProperty("lever_m_" + std::to_string(i + 1), std::to_string(lever[i]));
  }
  // Joint 6 turns the tool about its own axis: only the radii move.
  EXPECT_NEAR(lever[5], 0.035, 1e-9);  // the tool body's radius (wrist 3's housing is frame 5)
  EXPECT_LT(lever[4], 0.35);           // wrist 2 and the tool from the joint 5 axis
  EXPECT_LT(lever[3], 0.5);
  EXPECT_GE(lever[0], lever[1]);
  Joints a = Joints::Zero(), b = Joints::Zero();
  b[3] = b[4] = b[5] = 1.0;
  EXPECT_LT(3 * MotionSteps(a, b, 0.01, lever), MotionSteps(a, b, 0.01));
}

TEST(ReachOfPoint, HoldsThePointInEveryConfiguration) {
  const RobotModel robot = DefaultUr5(SecateurTool());
  std::mt19937 rng(1121);
  double widest = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const auto f = LinkFrames(RandomJoints(rng, robot.limits));
    for (const LinkBody& body : robot.BodiesWithTool()) {
      for (const Capsule& c : body.capsules) {
        for (const Eigen::Vector3d& e : {c.a, c.b}) {
          const ReachCylinder cyl = ReachOfPoint(body.frame, e);
          const Eigen::Vector3d p = f[body.frame] * e;
          ASSERT_LE(std::hypot(p.x(), p.y()), cyl.radius_m + 1e-12) << body.name;
          ASSERT_GE(p.z(), cyl.lo_z_m - 1e-12) << body.name;
          ASSERT_LE(p.z(), cyl.hi_z_m + 1e-12) << body.name;
          if (body.frame == 6) widest = std::max(widest, std::hypot(p.x(), p.y()) / cyl.radius_m);
        }
      }
    }
  }
  EXPECT_GT(widest, 0.8);  // not vacuous
}

TEST(CollisionChecker, MotionThroughAnObstacleIsNotFree) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  Joints a = Raised(), b = Raised();
  a[0] = -0.6;
  b[0] = 0.6;
  // A sphere on the tool tip's path at q1 = 0, beside neither end.
  CollisionScene scene;
  Obstacle o;
  const Eigen::Vector3d tip = ForwardKinematics(Raised()) * Eigen::Vector3d(0, 0, 0.17);
  o.capsule = {tip, tip, 0.01};
  scene.obstacles.push_back(o);
  for (FclMode mode : {FclMode::kPrimitives, FclMode::kMesh}) {
    auto fcl = MakeFclChecker(robot, scene, mode);
    EXPECT_FALSE(fcl->IsMotionFree(a, b, 0.005));
  }
  PrimitiveChecker checker(robot, scene);
  ASSERT_TRUE(checker.IsFree(a));
  ASSERT_TRUE(checker.IsFree(b));
  EXPECT_FALSE(checker.IsMotionFree(a, b, 0.005));
  checker.ResetChecks();
  Joints c = a;
  c[0] = -0.3;
  EXPECT_TRUE(checker.IsMotionFree(a, c, 0.005));
  EXPECT_EQ(checker.checks(), MotionSteps(a, c, 0.005, checker.lever_m()) + 1);
}

// Batched checks compute forward kinematics in float lanes: they may differ from IsFree only
// within float rounding of contact.
// The batched checks run AVX2 code where the CPU has it and the baseline SIMD code elsewhere;
// both are tested on every machine that can run them (kBaseline always).
enum class Simd { kDetected, kBaseline };

class PrimitiveCheckerSimd : public ::testing::TestWithParam<Simd> {
 protected:
  void Select(PrimitiveChecker& checker) const {
    if (GetParam() == Simd::kBaseline) {
      checker.UseBaselineSimd();
      EXPECT_FALSE(checker.uses_avx2());
    }
  }
};

INSTANTIATE_TEST_SUITE_P(Isa, PrimitiveCheckerSimd,
                         ::testing::Values(Simd::kDetected, Simd::kBaseline),
                         [](const auto& info) {
                           return info.param == Simd::kBaseline ? "Baseline" : "Detected";
                         });

TEST(PrimitiveChecker, UsesAvx2ExactlyWhenTheCpuHasIt) {
  PrimitiveChecker checker(DefaultUr5(SimpleMillEnd()), EmptyScene());
#if defined(__x86_64__)
  EXPECT_EQ(checker.uses_avx2(),
            __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"));
#else
  EXPECT_FALSE(checker.uses_avx2());
#endif
  checker.UseBaselineSimd();
  EXPECT_FALSE(checker.uses_avx2());
}

TEST_P(PrimitiveCheckerSimd, AreFreeAgreesWithIsFree) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  std::mt19937 rng(1130);
  int total = 0, free = 0, disagree = 0;
  for (uint64_t seed : {1130, 1131}) {
    PrimitiveChecker checker(robot, VineScene(seed, seed == 1131 ? 0.02 : 0.0));
    Select(checker);
    std::vector<Joints> qs;
    for (int k = 0; k < 2003; ++k) qs.push_back(RandomJoints(rng, robot.limits));
    std::unique_ptr<bool[]> flags(new bool[qs.size()]);
    checker.AreFree(qs, std::span<bool>(flags.get(), qs.size()));
    EXPECT_EQ(checker.checks(), static_cast<int64_t>(qs.size()));
    for (size_t k = 0; k < qs.size(); ++k) {
      const bool expected = checker.IsFree(qs[k]);
      ++total;
      free += expected;
      if (flags[k] != expected) {
        ++disagree;
        EXPECT_LT(std::abs(checker.Clearance(qs[k])), 2e-5) << "seed " << seed << " k " << k;
      }
    }
  }
  EXPECT_LE(disagree, total / 1000);
  EXPECT_GT(free, total / 20);
  EXPECT_LT(free, total - total / 20);
}

// The batched IsMotionFree against IsFree at every sample MotionSteps gives, on short motions
// around random configurations (both outcomes occur).
TEST_P(PrimitiveCheckerSimd, BatchedMotionAgreesWithSampledChecks) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  std::mt19937 rng(1132);
  int motions = 0, free = 0;
  for (uint64_t seed : {1132, 1133}) {
    PrimitiveChecker checker(robot, VineScene(seed));
    Select(checker);
    for (int trial = 0; trial < 300; ++trial) {
      const Joints a = RandomJoints(rng, robot.limits);
      const Joints b = a + (RandomJoints(rng, robot.limits) - a) * 0.1;
      const bool batched = checker.IsMotionFree(a, b, 0.01);
      const int n = MotionSteps(a, b, 0.01, checker.lever_m());
      bool expected = true, near_contact = false;
      for (int k = 0; k <= n; ++k) {
        const Joints q = a + (b - a) * (double(k) / n);
        expected = expected && checker.IsFree(q);
        near_contact = near_contact || std::abs(checker.Clearance(q)) < 2e-5;
      }
      ++motions;
      free += expected;
      if (batched != expected) {
        EXPECT_TRUE(near_contact) << "seed " << seed << " trial " << trial;
      }
    }
  }
  EXPECT_GT(free, motions / 10);
  EXPECT_LT(free, motions - motions / 10);
}

// Exact or conservative: configurations bisected (on the exact double Clearance) to within 1e-9 m
// inside contact are never free, by IsFree, AreFree or IsMotionFree, whatever SIMD code runs,
// although every test but Clearance is in float.
TEST_P(PrimitiveCheckerSimd, NeverFreeInContact) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  std::mt19937 rng(1136);
  int contacts = 0;
  for (uint64_t seed : {1136, 1137}) {
    PrimitiveChecker checker(robot, VineScene(seed, seed == 1137 ? 0.02 : 0.0));
    Select(checker);
    while (contacts < (seed == 1136 ? 150 : 300)) {
      const Joints a = RandomJoints(rng, robot.limits);
      const Joints b = RandomJoints(rng, robot.limits);
      if (!(checker.Clearance(a) > 0) || !(checker.Clearance(b) < 0)) continue;
      double lo = 0, hi = 1;  // Clearance(a + lo (b - a)) > 0 >= Clearance(a + hi (b - a))
      Joints inside = b;
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi);
        const Joints q = a + (b - a) * mid;
        const double c = checker.Clearance(q);
        if (c > 0) {
          lo = mid;
        } else {
          hi = mid, inside = q;
          if (c > -1e-9) break;
        }
      }
      const double clearance = checker.Clearance(inside);
      ASSERT_LE(clearance, 0.0);
      if (clearance < -1e-6) continue;  // the boundary is not continuous here (a new contact)
      ++contacts;
      EXPECT_FALSE(checker.IsFree(inside)) << "seed " << seed << " clearance " << clearance;
      std::vector<Joints> qs(9, inside);
      bool out[9];
      checker.AreFree(qs, out);
      EXPECT_FALSE(out[0]) << "seed " << seed << " clearance " << clearance;
      EXPECT_FALSE(checker.IsMotionFree(a, inside, 0.01)) << "seed " << seed;
    }
  }
  EXPECT_EQ(contacts, 300);
}

// The AVX2 code (8 lanes) and the baseline code (4 lanes) give the same answers on motions of
// every length (they differ only by float rounding, so only within 2e-5 m of contact: the 1e-5 m
// padding of the float tests plus rounding).
TEST(PrimitiveChecker, DetectedAndBaselineSimdAgreeOnMotions) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  std::mt19937 rng(1134);
  int motions = 0, free = 0, disagree = 0;
  for (uint64_t seed : {1134, 1135}) {
    const CollisionScene scene = VineScene(seed, seed == 1135 ? 0.02 : 0.0);
    PrimitiveChecker detected(robot, scene), baseline(robot, scene);
    baseline.UseBaselineSimd();
    std::vector<Joints> free_qs;
    for (int k = 0; free_qs.size() < 200 && k < 20000; ++k) {
      const Joints q = RandomJoints(rng, robot.limits);
      if (baseline.IsFree(q)) free_qs.push_back(q);
    }
    for (size_t k = 0; k + 1 < free_qs.size(); ++k) {
      for (double fraction : {0.02, 0.1, 0.3, 1.0}) {
        const Joints a = free_qs[k];
        const Joints b = a + (free_qs[k + 1] - a) * fraction;
        const bool expected = baseline.IsMotionFree(a, b, 0.01);
        ++motions;
        free += expected;
        if (detected.IsMotionFree(a, b, 0.01) != expected) {
          ++disagree;
          const int n = MotionSteps(a, b, 0.01, baseline.lever_m());
          double closest = 1e9;
          for (int i = 0; i <= n; ++i) {
            closest = std::min(closest, std::abs(baseline.Clearance(a + (b - a) * (double(i) / n))));
          }
          EXPECT_LT(closest, 2e-5) << "seed " << seed << " k " << k << " fraction " << fraction;
        }
      }
    }
  }
  EXPECT_LE(disagree, motions / 200);
  EXPECT_GT(free, motions / 10);
  EXPECT_LT(free, motions - motions / 10);
}

// The acceptance test of issue 5: the primitive checker and both FCL baselines agree on >= 99.9%
// of random configurations within the joint limits, and every disagreement lies within the
// tessellation tolerance (meshes) or numerical noise (FCL primitives) of contact.
TEST(CheckerAgreement, PrimitivesAndFclAgreeOnRandomConfigurations) {
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  std::mt19937 rng(1110);
  int total = 0, free = 0, disagree_primitives = 0, disagree_mesh = 0;
  for (uint64_t seed : {1110, 1111, 1112}) {
    const CollisionScene scene = VineScene(seed, seed == 1111 ? 0.02 : 0.0);
    PrimitiveChecker ours(robot, scene);
    auto fcl_primitives = MakeFclChecker(robot, scene, FclMode::kPrimitives);
    auto fcl_mesh = MakeFclChecker(robot, scene, FclMode::kMesh);
    // Vertices on the surface: the meshes of the arm and of an obstacle can each be inside the
    // true surface by up to the tolerance.
    const double mesh_tolerance = 2.0 * MeshToleranceM(robot, scene);
    EXPECT_LT(mesh_tolerance, 0.003);
    for (int trial = 0; trial < 1500; ++trial) {
      const Joints q = RandomJoints(rng, robot.limits);
      const bool expected = ours.IsFree(q);
      ++total;
      free += expected;
      if (fcl_primitives->IsFree(q) != expected) {
        ++disagree_primitives;
        // Our float tests pad the arm by 1e-5 m (conservative): a disagreement lies within
        // that padding plus rounding of contact.
        EXPECT_LT(std::abs(ours.Clearance(q)), 2e-5) << "seed " << seed << " trial " << trial;
      }
      if (fcl_mesh->IsFree(q) != expected) {
        ++disagree_mesh;
        const double clearance = ours.Clearance(q);
        EXPECT_LE(clearance, 1e-9) << "the mesh lies inside the true surface";
        EXPECT_GT(clearance, -mesh_tolerance) << "seed " << seed << " trial " << trial;
      }
    }
  }
  EXPECT_LE(disagree_primitives, total / 1000);
  EXPECT_LE(disagree_mesh, total / 1000);
  // Random configurations must exercise both outcomes for the comparison to mean anything.
  EXPECT_GT(free, total / 20);
  EXPECT_LT(free, total - total / 20);
  RecordProperty("free_fraction", std::to_string(double(free) / total));
  RecordProperty("configurations", total);
  RecordProperty("disagree_fcl_primitives", disagree_primitives);
  RecordProperty("disagree_fcl_mesh", disagree_mesh);
}

}  // namespace
}  // namespace vb::plan
