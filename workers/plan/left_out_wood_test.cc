// SPDX-License-Identifier: Apache-2.0
// The wood the model leaves out (VineModel::obstacles) in the plan: in the collision scene as
// chords like a cane's, never left out as the cut cane is, kept when wood falls, avoided by the
// whole plan.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "core/trajectory.h"
#include "core/vine_model_json.h"
#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/decide/decide.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/fallen_wood.h"
#include "workers/plan/plan_vine.h"
#include "workers/plan/tool.h"
#include "workers/plan/trajectory_check.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {
namespace {

VineModel SimVine(uint64_t seed) {
  auto scene = sim::GenerateScene(seed, 1);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return scene->vine;
}

WoodObstacle Wood(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius_m) {
  WoodObstacle o;
  o.polyline.points = {a, 0.5 * (a + b), b};
  o.polyline.radii = {radius_m, radius_m, radius_m};
  return o;
}

TEST(LeftOutWood, SceneHoldsItsChordsAndNoCutLeavesThemOut) {
  const VineModel vine = SimVine(1100);
  const RobotModel robot = DefaultUr5(MillEndTool());
  VineModel with = vine;
  // Across the second cane's middle, and a second piece elsewhere.
  const Polyline3& cane = vine.canes[1].polyline;
  const Eigen::Vector3d mid = cane.PointAt(0.5 * cane.Length());
  with.obstacles = {Wood(mid + Eigen::Vector3d(0, -0.05, -0.1), mid + Eigen::Vector3d(0, 0.05, 0.1),
                         0.005),
                    Wood({-0.6, 0.8, 1.2}, {-0.4, 0.75, 1.25}, 0.004)};
  const auto without_scene = CollisionScene::Build(vine, DefaultPlatform(), robot);
  const auto scene = CollisionScene::Build(with, DefaultPlatform(), robot);
  ASSERT_TRUE(without_scene.ok()) << without_scene.status();
  ASSERT_TRUE(scene.ok()) << scene.status();
  // Everything else as before, in the same order.
  std::vector<Obstacle> rest;
  for (const Obstacle& o : scene->obstacles)
    if (o.kind != ObstacleKind::kLeftOutWood) rest.push_back(o);
  ASSERT_EQ(rest.size(), without_scene->obstacles.size());
  for (size_t i = 0; i < rest.size(); ++i) {
    EXPECT_EQ(rest[i].kind, without_scene->obstacles[i].kind);
    EXPECT_EQ(rest[i].capsule.a, without_scene->obstacles[i].capsule.a);
    EXPECT_EQ(rest[i].capsule.radius, without_scene->obstacles[i].capsule.radius);
  }
  // The chords enclose each piece of wood (the 0.23 m piece in eight 0.03 m chords).
  const Eigen::Isometry3d base_from_platform = robot.platform_from_arm_base.inverse();
  for (size_t w = 0; w < with.obstacles.size(); ++w) {
    SCOPED_TRACE(w);
    const Polyline3& wood = with.obstacles[w].polyline;
    int chords = 0;
    for (const Obstacle& o : scene->obstacles)
      chords += o.kind == ObstacleKind::kLeftOutWood && o.owner_id == static_cast<int64_t>(w) + 1;
    EXPECT_EQ(chords, static_cast<int>(std::ceil(wood.Length() / 0.03 - 1e-6)));
    for (double s = 0; s <= wood.Length(); s += 0.002) {
      const Eigen::Vector3d p = base_from_platform * wood.PointAt(s);
      double worst = 1e9;
      for (const Obstacle& o : scene->obstacles) {
        if (o.kind != ObstacleKind::kLeftOutWood || o.owner_id != static_cast<int64_t>(w) + 1)
          continue;
        worst = std::min(worst, PointSegmentDistance(p, o.capsule.a, o.capsule.b) - o.capsule.radius);
      }
      EXPECT_LE(worst, -wood.RadiusAt(s) + 1e-9) << "s " << s;
    }
  }
  // A cut on any cane, right on the wood, with the largest radius: the wood stays (its owner ids
  // 1 and 2 are those of canes, too).
  for (const Cane& c : vine.canes) {
    const CollisionScene cut = scene->WithoutCaneNear(c.id, base_from_platform * mid, 10.0);
    EXPECT_EQ(std::count_if(cut.obstacles.begin(), cut.obstacles.end(),
                            [](const Obstacle& o) { return o.kind == ObstacleKind::kLeftOutWood; }),
              std::count_if(scene->obstacles.begin(), scene->obstacles.end(),
                            [](const Obstacle& o) { return o.kind == ObstacleKind::kLeftOutWood; }));
  }
  // Wood falling with cuts leaves it where it is.
  Cut remove_all;
  remove_all.cane_id = vine.canes[1].id;
  remove_all.point = cane.points.front();
  EXPECT_EQ(WithoutFallenWood(with, std::vector<Cut>{remove_all}).obstacles.size(), 2u);
}

// Wood put where the arm passed on a plan made without it: the old trajectory hits it, the plan
// made with it does not, and still makes cuts.
TEST(LeftOutWood, ThePlanAvoidsIt) {
  const VineModel vine = SimVine(1101);
  auto decision = decide::Decide(vine, PruningPolicy{});
  ASSERT_TRUE(decision.ok()) << decision.status();
  const RobotModel robot = DefaultUr5(MillEndTool());
  const PlatformGeometry platform = DefaultPlatform();
  PlanOptions options;
  options.home = DefaultHome();
  const auto before = PlanVine(vine, decision->plan, robot, platform, options);
  ASSERT_TRUE(before.ok()) << before.status();
  // The middle of the longest transit between two cuts: the flange's centre there.
  const TrajectorySegment* longest = nullptr;
  const auto& segments = before->trajectory.segments;
  for (size_t i = 1; i + 1 < segments.size(); ++i) {
    if (segments[i].kind != SegmentKind::kTransit) continue;
    if (longest == nullptr || segments[i].points.size() > longest->points.size())
      longest = &segments[i];
  }
  ASSERT_NE(longest, nullptr);
  const TrajectoryPoint& middle = longest->points[longest->points.size() / 2];
  const Joints q = Eigen::Map<const Joints>(middle.q.data());
  const Eigen::Vector3d flange = robot.platform_from_arm_base * ForwardKinematics(q).translation();
  VineModel with = vine;
  with.obstacles = {Wood(flange - Eigen::Vector3d(0.03, 0, 0), flange + Eigen::Vector3d(0.03, 0, 0),
                         0.01)};
  const double cut_radius = options.cut_motion.cut_cane_free_radius_m;
  EXPECT_GT(CountTrajectoryCollisions(before->trajectory, before->cuts, with, platform, robot,
                                      CheckerKind::kPrimitives, 0.002, cut_radius),
            0);
  const auto after = PlanVine(with, decision->plan, robot, platform, options);
  ASSERT_TRUE(after.ok()) << after.status();
  EXPECT_FALSE(after->cuts.empty());
  EXPECT_EQ(CountTrajectoryCollisions(after->trajectory, after->cuts, with, platform, robot,
                                      CheckerKind::kPrimitives, 0.002, cut_radius),
            0);
}

// A report, not a check: for each stop directory in VB_LEFT_OUT_STOPS (separated by spaces) whose
// model.json carries left-out wood and whose trajectory_without.json was planned by `vinebot plan`
// (secateur) on the model without it, the segments and configurations of that trajectory that
// touch the wood (at 2 mm of travel; the wood alone, nothing else of the vine or platform).
// VB_LEFT_OUT_TRAJECTORY names another trajectory file in each directory (e.g. one planned with
// the wood, which must touch none).
TEST(LeftOutWood, DISABLED_ReportPlansMadeWithoutIt) {
  const char* stops = std::getenv("VB_LEFT_OUT_STOPS");
  if (stops == nullptr) GTEST_SKIP() << "set VB_LEFT_OUT_STOPS";
  const RobotModel robot = DefaultUr5(SecateurTool());
  PlatformGeometry nothing;  // walls far away, no cameras: the wood alone
  nothing.ground_z_m = -10;
  nothing.roof_z_m = 10;
  nothing.camera_side_wall_y_m = -10;
  nothing.backdrop_y_m = 10;
  std::istringstream list(stops);
  std::string dir;
  int stops_hit = 0, stops_seen = 0;
  while (list >> dir) {
    const auto model = ReadVineModel(dir + "/model.json");
    const char* name = std::getenv("VB_LEFT_OUT_TRAJECTORY");
    const auto trajectory =
        ReadTrajectory(dir + "/" + (name != nullptr ? name : "trajectory_without.json"));
    ASSERT_TRUE(model.ok()) << model.status();
    ASSERT_TRUE(trajectory.ok()) << trajectory.status();
    VineModel wood;
    wood.obstacles = model->obstacles;
    double length = 0;
    for (const WoodObstacle& o : wood.obstacles) length += o.polyline.Length();
    std::vector<int> bad;
    const int64_t hits = CountTrajectoryCollisions(*trajectory, {}, wood, nothing, robot,
                                                   CheckerKind::kPrimitives, 0.002, 0.0, &bad);
    const int bad_segments = static_cast<int>(std::count_if(bad.begin(), bad.end(),
                                                            [](int b) { return b > 0; }));
    ++stops_seen;
    stops_hit += hits > 0;
    std::printf("%s: %zu pieces of wood, %.2f m; %lld configurations touch it, in %d of %zu "
                "segments\n",
                dir.c_str(), wood.obstacles.size(), length, static_cast<long long>(hits),
                bad_segments, trajectory->segments.size());
  }
  std::printf("stops whose trajectory touches the wood: %d of %d\n", stops_hit, stops_seen);
}

}  // namespace
}  // namespace vb::plan
