// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/safety_margins.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/tool.h"

namespace vb::plan {
namespace {

// The first implementation of InflateMargins, kept as the reference the fast one must reproduce:
// every obstacle against every arm capsule at every protected configuration, culled only by
// bounding spheres.
MarginSummary ReferenceInflateMargins(const RobotModel& robot,
                                      std::span<const ProtectedMotion> motions,
                                      const MarginOptions& options, CollisionScene* scene) {
  struct PlacedCapsule {
    Eigen::Vector3d a, b, centre;
    double radius = 0.0;
    double bound = 0.0;
  };
  struct Pose {
    std::vector<PlacedCapsule> bodies;
    const ProtectedMotion* motion = nullptr;
  };
  const std::vector<LinkBody> bodies = robot.BodiesWithTool();
  auto place = [&](const Joints& q, const ProtectedMotion* motion) {
    const auto frames = LinkFrames(q);
    Pose pose;
    pose.motion = motion;
    for (const LinkBody& body : bodies) {
      for (const Capsule& c : body.capsules) {
        PlacedCapsule p;
        p.a = frames[body.frame] * c.a;
        p.b = frames[body.frame] * c.b;
        p.centre = 0.5 * (p.a + p.b);
        p.radius = c.radius;
        p.bound = 0.5 * (p.b - p.a).norm() + c.radius;
        pose.bodies.push_back(p);
      }
    }
    return pose;
  };
  // WithoutCaneNear's capsules, written out: the surface within the radius of the cut point.
  auto ignored = [](const Obstacle& o, const ProtectedMotion& m) {
    return m.ignored_cane.value != 0 && o.kind == ObstacleKind::kCane &&
           o.owner_id == m.ignored_cane.value &&
           PointSegmentDistance(m.ignored_point_in_base, o.capsule.a, o.capsule.b) -
                   o.capsule.radius <=
               m.ignored_radius_m;
  };
  const JointLevers lever_m = JointLeverArms(robot);
  std::vector<Pose> poses;
  for (const ProtectedMotion& motion : motions) {
    for (size_t i = 0; i < motion.path.size(); ++i) {
      poses.push_back(place(motion.path[i], &motion));
      if (i + 1 == motion.path.size()) break;
      const Joints& a = motion.path[i];
      const Joints& b = motion.path[i + 1];
      const int steps = MotionSteps(a, b, options.max_step_m, lever_m);
      for (int s = 1; s < steps; ++s) poses.push_back(place(a + (b - a) * (double(s) / steps), &motion));
    }
  }
  const double reach = options.max_margin_m + options.slack_m;
  std::vector<double> vine_margins;
  for (Obstacle& o : scene->obstacles) {
    const Eigen::Vector3d centre = 0.5 * (o.capsule.a + o.capsule.b);
    const double bound = 0.5 * (o.capsule.b - o.capsule.a).norm() + o.capsule.radius;
    double clearance = std::numeric_limits<double>::infinity();
    for (const Pose& pose : poses) {
      if (ignored(o, *pose.motion)) continue;
      for (const PlacedCapsule& p : pose.bodies) {
        if ((p.centre - centre).norm() - p.bound - bound > reach) continue;
        const double d = SegmentSegmentDistance(p.a, p.b, o.capsule.a, o.capsule.b) - p.radius -
                         o.capsule.radius;
        clearance = std::min(clearance, d);
      }
    }
    o.margin_m = std::clamp(clearance - options.slack_m, 0.0, options.max_margin_m);
    if (o.kind != ObstacleKind::kPlatform) vine_margins.push_back(o.margin_m);
  }
  for (HalfSpace& plane : scene->planes) {
    double clearance = std::numeric_limits<double>::infinity();
    for (const Pose& pose : poses) {
      for (const PlacedCapsule& p : pose.bodies) {
        const double d = plane.offset - std::max(plane.normal.dot(p.a), plane.normal.dot(p.b)) -
                         p.radius;
        clearance = std::min(clearance, d);
      }
    }
    plane.margin_m = std::clamp(clearance - options.slack_m, 0.0, options.max_margin_m);
  }
  MarginSummary summary;
  summary.configurations = static_cast<int>(poses.size());
  if (!vine_margins.empty()) {
    std::sort(vine_margins.begin(), vine_margins.end());
    summary.min_margin_m = vine_margins.front();
    summary.median_margin_m = vine_margins[vine_margins.size() / 2];
  }
  return summary;
}

// A robot of one fixed body: a vertical capsule at the base origin, 0.1 m long, radius 0.05.
// Where it is does not depend on q, so clearances are known in closed form.
RobotModel Post() {
  RobotModel robot;
  robot.links.push_back({"base", 0, {Capsule{Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 0.1), 0.05}}});
  return robot;
}

Obstacle Ball(double x, double radius, ObstacleKind kind = ObstacleKind::kHead, int64_t owner = 0) {
  Obstacle o;
  o.kind = kind;
  o.owner_id = owner;
  o.capsule = {Eigen::Vector3d(x, 0, 0.05), Eigen::Vector3d(x, 0, 0.05), radius};
  return o;
}

std::vector<ProtectedMotion> Still() { return {{{Joints::Zero()}, CaneId{0}, Eigen::Vector3d::Zero(), 0.0}}; }

TEST(SafetyMargins, FarObstaclesGetTheMaximum) {
  CollisionScene scene;
  scene.obstacles.push_back(Ball(1.0, 0.01));
  MarginOptions options;
  const MarginSummary summary = InflateMargins(Post(), Still(), options, &scene);
  EXPECT_DOUBLE_EQ(scene.obstacles[0].margin_m, options.max_margin_m);
  EXPECT_EQ(summary.configurations, 1);
}

TEST(SafetyMargins, NearObstaclesStopShortOfTheProtectedBody) {
  CollisionScene scene;
  // Surface gap: 0.07 - 0.05 - 0.01 = 0.01 m.
  scene.obstacles.push_back(Ball(0.07, 0.01));
  MarginOptions options;
  options.slack_m = 0.002;
  InflateMargins(Post(), Still(), options, &scene);
  EXPECT_NEAR(scene.obstacles[0].margin_m, 0.008, 1e-12);
}

TEST(SafetyMargins, TouchingObstaclesGetNone) {
  CollisionScene scene;
  scene.obstacles.push_back(Ball(0.055, 0.01));
  InflateMargins(Post(), Still(), MarginOptions{}, &scene);
  EXPECT_EQ(scene.obstacles[0].margin_m, 0.0);
}

TEST(SafetyMargins, TheCutCaneNearTheCutDoesNotLimitItsMargin) {
  CollisionScene scene;
  scene.obstacles.push_back(Ball(0.055, 0.01, ObstacleKind::kCane, 7));
  scene.obstacles.push_back(Ball(0.055, 0.01, ObstacleKind::kCane, 8));
  std::vector<ProtectedMotion> cut = {
      {{Joints::Zero()}, CaneId{7}, Eigen::Vector3d(0.05, 0, 0.05), 0.02}};
  MarginOptions options;
  InflateMargins(Post(), cut, options, &scene);
  EXPECT_DOUBLE_EQ(scene.obstacles[0].margin_m, options.max_margin_m);  // cane 7: ignored there
  EXPECT_EQ(scene.obstacles[1].margin_m, 0.0);                          // cane 8: touching
}

// A cut motion ignores exactly the capsules of its cane that the cut motions' checkers leave out
// (CollisionScene::CaneNearIndices): those whose surface, not axis, is within the radius.
TEST(SafetyMargins, TheCutCaneIsIgnoredWhereWithoutCaneNearLeavesItOut) {
  CollisionScene scene;
  // Balls of cane 7, each touching the post (gap < 0): axis 15-30 mm from the cut point, radius
  // 10 mm, so their surfaces are 5-20 mm from it; the rule's radius is 12 mm.
  for (double dz : {0.015, 0.02, 0.021, 0.023, 0.025, 0.03}) {
    Obstacle o = Ball(0.055, 0.01, ObstacleKind::kCane, 7);
    o.capsule.a.z() += dz;
    o.capsule.b.z() += dz;
    scene.obstacles.push_back(o);
  }
  const Eigen::Vector3d cut(0.055, 0, 0.05);
  const double radius_m = 0.012;
  const std::vector<int> near = scene.CaneNearIndices(CaneId{7}, cut, radius_m);
  ASSERT_EQ(near, (std::vector<int>{0, 1, 2}));  // surfaces 5, 10, 11 mm away
  const std::vector<ProtectedMotion> motion = {{{Joints::Zero()}, CaneId{7}, cut, radius_m}};
  MarginOptions options;
  InflateMargins(Post(), motion, options, &scene);
  for (int i = 0; i < static_cast<int>(scene.obstacles.size()); ++i) {
    const bool left_out = std::find(near.begin(), near.end(), i) != near.end();
    EXPECT_DOUBLE_EQ(scene.obstacles[i].margin_m, left_out ? options.max_margin_m : 0.0) << i;
  }
}

// The same configuration in several motions (as a stroke's ends are, and alternatives share):
// an obstacle ignores it only where every motion that holds it ignores that obstacle.
TEST(SafetyMargins, ASharedConfigurationIsIgnoredOnlyWhereEveryMotionIgnoresIt) {
  const Eigen::Vector3d cut(0.05, 0, 0.05);
  const ProtectedMotion cut7 = {{Joints::Zero()}, CaneId{7}, cut, 0.02};
  const ProtectedMotion cut8 = {{Joints::Zero()}, CaneId{8}, cut, 0.02};
  const ProtectedMotion end = {{Joints::Zero()}, CaneId{0}, Eigen::Vector3d::Zero(), 0.0};
  const MarginOptions options;
  auto margins = [&](const std::vector<ProtectedMotion>& motions) {
    CollisionScene scene;
    scene.obstacles.push_back(Ball(0.055, 0.01, ObstacleKind::kCane, 7));
    scene.obstacles.push_back(Ball(0.055, 0.01, ObstacleKind::kCane, 8));
    const MarginSummary summary = InflateMargins(Post(), motions, options, &scene);
    EXPECT_EQ(summary.configurations, static_cast<int>(motions.size()));
    return std::pair(scene.obstacles[0].margin_m, scene.obstacles[1].margin_m);
  };
  // Ignoring nothing, before or after the cut: both canes touch.
  EXPECT_EQ(margins({cut7, end}), std::pair(0.0, 0.0));
  EXPECT_EQ(margins({end, cut7}), std::pair(0.0, 0.0));
  // Two cuts on different canes: each cane is protected by the other cut.
  EXPECT_EQ(margins({cut7, cut8}), std::pair(0.0, 0.0));
  // Two motions on the same cane: it is ignored by both.
  EXPECT_EQ(margins({cut7, cut7}), std::pair(options.max_margin_m, 0.0));
}

TEST(SafetyMargins, PlanesKeepTheirDistance) {
  CollisionScene scene;
  HalfSpace ground;  // free side: z >= -0.02, i.e. -z <= 0.02
  ground.normal = Eigen::Vector3d(0, 0, -1);
  ground.offset = 0.02;
  scene.planes.push_back(ground);
  MarginOptions options;
  options.slack_m = 0.0;
  InflateMargins(Post(), Still(), options, &scene);
  // Lowest body point: z = -0.05; distance to the plane z = -0.02 is negative: no margin.
  EXPECT_EQ(scene.planes[0].margin_m, 0.0);
  scene.planes[0].offset = 0.07;  // plane at z = -0.07: 0.02 m below the body
  InflateMargins(Post(), Still(), options, &scene);
  EXPECT_NEAR(scene.planes[0].margin_m, 0.02, 1e-12);
}

// Random protected motions on simulated vines (seeds 1100-1105): short joint paths around random
// configurations, half of them allowed to touch a random cane near a random point of it, plus a
// long motion (the home-to-start kind). The fast implementation must give every obstacle and
// plane the reference's margin.
TEST(SafetyMargins, MatchesTheReferenceOnSimulatedVines) {
  const RobotModel robot = DefaultUr5(MillEndTool());
  std::mt19937_64 rng(1100);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), step(-0.15, 0.15);
  int between = 0, obstacles = 0;
  for (uint64_t seed = 1100; seed < 1106; ++seed) {
    auto generated = sim::GenerateScene(seed, 0, sim::VineGeneratorOptions{});
    ASSERT_TRUE(generated.ok()) << generated.status();
    auto scene = CollisionScene::Build(generated->vine, DefaultPlatform(), robot);
    ASSERT_TRUE(scene.ok()) << scene.status();
    std::vector<const Obstacle*> canes;
    for (const Obstacle& o : scene->obstacles)
      if (o.kind == ObstacleKind::kCane) canes.push_back(&o);
    ASSERT_FALSE(canes.empty());
    std::vector<ProtectedMotion> motions;
    for (int m = 0; m < 40; ++m) {
      ProtectedMotion motion;
      Joints q;
      for (int j = 0; j < 6; ++j) q[j] = angle(rng);
      for (int k = 0; k < 6; ++k) {
        motion.path.push_back(q);
        for (int j = 0; j < 6; ++j) q[j] += step(rng);
      }
      if (m % 2 == 1) {
        const Obstacle& cane = *canes[rng() % canes.size()];
        motion.ignored_cane = CaneId{cane.owner_id};
        motion.ignored_point_in_base = cane.capsule.a;
        motion.ignored_radius_m = 0.04;
      }
      motions.push_back(motion);
    }
    // Motions that share configurations (placed once by the fast pass): a copy of a motion that
    // ignores nothing, allowed to touch a cane (the configurations stay protected from it); a
    // copy of one that ignores a cane, ignoring another (each cane stays protected by the other
    // motion); a copy ignoring the same cane (ignored by both); and a motion's first
    // configuration alone (as PlanVine protects a stroke's ends).
    for (int m = 0; m < 8; ++m) {
      ProtectedMotion copy = motions[m];
      const Obstacle& cane = *canes[rng() % canes.size()];
      if (m % 4 != 3) {
        copy.ignored_cane = CaneId{cane.owner_id};
        copy.ignored_point_in_base = cane.capsule.a;
        copy.ignored_radius_m = 0.04;
      }
      if (m % 4 == 3) copy.path.resize(1);
      motions.push_back(copy);
    }
    Joints home, away;
    for (int j = 0; j < 6; ++j) home[j] = angle(rng), away[j] = angle(rng);
    motions.push_back({{home, away}, CaneId{0}, Eigen::Vector3d::Zero(), 0.0});
    for (const double max_margin_m : {0.03, 0.1}) {
      MarginOptions options;
      options.max_margin_m = max_margin_m;
      CollisionScene fast = *scene, reference = *scene;
      const MarginSummary fast_summary = InflateMargins(robot, motions, options, &fast);
      const MarginSummary reference_summary =
          ReferenceInflateMargins(robot, motions, options, &reference);
      EXPECT_EQ(fast_summary.configurations, reference_summary.configurations);
      EXPECT_NEAR(fast_summary.min_margin_m, reference_summary.min_margin_m, 1e-9);
      EXPECT_NEAR(fast_summary.median_margin_m, reference_summary.median_margin_m, 1e-9);
      ASSERT_EQ(fast.obstacles.size(), reference.obstacles.size());
      for (size_t i = 0; i < fast.obstacles.size(); ++i) {
        EXPECT_NEAR(fast.obstacles[i].margin_m, reference.obstacles[i].margin_m, 1e-9)
            << "seed " << seed << " obstacle " << i;
        const double m = reference.obstacles[i].margin_m;
        between += m > 0 && m < max_margin_m;
        ++obstacles;
      }
      for (size_t i = 0; i < fast.planes.size(); ++i)
        EXPECT_NEAR(fast.planes[i].margin_m, reference.planes[i].margin_m, 1e-9);
    }
  }
  // The scenes must exercise partial margins, not only 0 and the maximum.
  EXPECT_GT(between, obstacles / 50) << between << " of " << obstacles;
}

// Planes moved so that each is 15 mm from long motions (hundreds of configurations: many chunks
// and blocks, most far from the plane): the planes' chunk bounds must not skip the nearest
// capsule, so every plane gets the reference's partial margin.
TEST(SafetyMargins, PartialPlaneMarginsMatchTheReference) {
  const RobotModel robot = DefaultUr5(MillEndTool());
  auto scene = CollisionScene::Build(VineModel{},
                                     DefaultPlatform(), robot);
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_FALSE(scene->planes.empty());
  std::mt19937_64 rng(1101);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::vector<ProtectedMotion> motions;
  for (int m = 0; m < 3; ++m) {
    ProtectedMotion motion;
    for (int k = 0; k < 3; ++k) {
      Joints q;
      for (int j = 0; j < 6; ++j) q[j] = angle(rng);
      motion.path.push_back(q);
    }
    motions.push_back(motion);
  }
  MarginOptions far;
  far.max_margin_m = 1e6;  // the true clearances
  for (HalfSpace& plane : scene->planes) plane.offset += 10.0;  // every motion on its free side
  CollisionScene measured = *scene;
  ReferenceInflateMargins(robot, motions, far, &measured);
  for (size_t i = 0; i < scene->planes.size(); ++i)
    scene->planes[i].offset -= measured.planes[i].margin_m - 0.015;
  MarginOptions options;
  CollisionScene fast = *scene, reference = *scene;
  const MarginSummary summary = InflateMargins(robot, motions, options, &fast);
  ReferenceInflateMargins(robot, motions, options, &reference);
  EXPECT_GT(summary.configurations, 300);
  for (size_t i = 0; i < fast.planes.size(); ++i) {
    EXPECT_NEAR(reference.planes[i].margin_m, 0.015, 1e-9) << "plane " << i;
    EXPECT_NEAR(fast.planes[i].margin_m, reference.planes[i].margin_m, 1e-12) << "plane " << i;
  }
}

TEST(TwistCachedFrames, GivesLinkFramesBitForBit) {
  // The margins are compared bit for bit between builds (vb_margins_bench's fingerprint), so the
  // placement must not differ from LinkFrames in the last bit, anywhere in the joint range.
  const TwistCachedFrames frames;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-2 * M_PI, 2 * M_PI);
  int differing = 0;
  for (int n = 0; n < 20000; ++n) {
    Joints q;
    for (int j = 0; j < 6; ++j) q[j] = angle(rng);
    if (n % 4 == 0) q[n % 6] = 0.0;  // exact zeros, as home and some IK solutions have
    const auto expected = LinkFrames(q);
    const auto got = frames(q);
    for (int f = 0; f < 7; ++f)
      differing += !(expected[f].matrix().array() == got[f].matrix().array()).all();
  }
  EXPECT_EQ(differing, 0);
  // Other DH parameters are honoured too.
  DhParameters dh = Ur5Dh();
  dh.alpha[1] = 0.3;
  dh.a[2] = -0.5;
  const Joints q = (Joints() << 0.1, -0.7, 1.2, 0.4, -0.9, 2.0).finished();
  EXPECT_TRUE((TwistCachedFrames(dh)(q)[6].matrix().array() ==
               LinkFrames(q, dh)[6].matrix().array()).all());
  EXPECT_FALSE((TwistCachedFrames(dh)(q)[6].matrix().array() ==
                LinkFrames(q)[6].matrix().array()).all());
}

TEST(SafetyMargins, OptionsRejectBadValues) {
  MarginOptions options;
  options.max_step_m = 0.0;
  EXPECT_NE(options.Validate().message().find("max_step_m"), std::string::npos);
  options = MarginOptions();
  options.max_margin_m = -1;
  EXPECT_NE(options.Validate().message().find("max_margin_m"), std::string::npos);
}

}  // namespace
}  // namespace vb::plan
