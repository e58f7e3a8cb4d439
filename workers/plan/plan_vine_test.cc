// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/plan_vine.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/decide/decide.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/cut_motion.h"
#include "workers/plan/fallen_wood.h"
#include "workers/plan/motion_prover.h"
#include "workers/plan/tool.h"
#include "workers/plan/trajectory_check.h"

namespace vb::plan {
namespace {

struct Stop {
  VineModel model;
  CutPlan plan;
};

// A simulated vine (tuning seeds) and its cut plan under the default policy.
Stop SimStop(uint64_t seed) {
  auto scene = sim::GenerateScene(seed, 1);
  EXPECT_TRUE(scene.ok()) << scene.status();
  auto decision = decide::Decide(scene->vine, PruningPolicy{});
  EXPECT_TRUE(decision.ok()) << decision.status();
  return {scene->vine, decision->plan};
}

PlanOptions Options() {
  PlanOptions options;
  options.home = DefaultHome();
  return options;
}

Joints At(const TrajectoryPoint& p) { return Eigen::Map<const Joints>(p.q.data()); }

TEST(PlanVine, PlansSimulatedVinesWithoutTouchingThem) {
  const RobotModel robot = DefaultUr5(MillEndTool());
  const PlatformGeometry platform = DefaultPlatform();
  int planned = 0;
  for (uint64_t seed : {1100, 1101, 1102}) {
    const Stop stop = SimStop(seed);
    auto result = PlanVine(stop.model, stop.plan, robot, platform, Options());
    ASSERT_TRUE(result.ok()) << result.status();
    const Trajectory& t = result->trajectory;
    EXPECT_TRUE(t.Validate().ok()) << t.Validate();
    // Every cut ends planned or unplanned with a reason, never both, never lost.
    std::set<int64_t> accounted;
    for (const Cut& c : result->cuts) EXPECT_TRUE(accounted.insert(c.id.value).second);
    for (const UnplannedCut& u : t.unplanned) {
      EXPECT_TRUE(accounted.insert(u.cut_id.value).second);
      EXPECT_FALSE(u.reason.empty());
    }
    EXPECT_EQ(accounted.size(), stop.plan.cuts.size());
    planned += static_cast<int>(result->cuts.size());
    if (result->cuts.empty()) continue;
    // One cut segment per planned cut; the arm leaves home and comes back.
    int cut_segments = 0;
    for (const TrajectorySegment& s : t.segments) cut_segments += s.kind == SegmentKind::kCut;
    EXPECT_EQ(cut_segments, static_cast<int>(result->cuts.size()));
    EXPECT_TRUE(At(t.segments.front().points.front()).isApprox(DefaultHome(), 1e-9));
    EXPECT_TRUE(At(t.segments.back().points.back()).isApprox(DefaultHome(), 1e-9));
    EXPECT_GT(t.duration_s, 0.0);
    // Re-checked at 2 mm of travel without the margins it was planned with: no contact.
    std::vector<int> bad;
    EXPECT_EQ(CountTrajectoryCollisions(t, result->cuts, stop.model, platform, robot,
                                        CheckerKind::kPrimitives, 0.002,
                                        Options().cut_motion.cut_cane_free_radius_m, &bad),
              0)
        << "seed " << seed;
  }
  EXPECT_GT(planned, 0);
}

// Finite differences of every segment: velocity within the limits, at rest at both ends, times
// strictly increasing; on transits (blended, piecewise constant acceleration) the second
// divided differences, weighted means of the acceleration, within the acceleration limits too.
void ExpectTimingWithinLimits(const Trajectory& t, const JointLimits& limits) {
  for (const TrajectorySegment& s : t.segments) {
    ASSERT_GE(s.points.size(), 2u);
    for (size_t p = 1; p < s.points.size(); ++p) {
      const double dt = s.points[p].t - s.points[p - 1].t;
      ASSERT_GT(dt, 0.0);
      const Joints v = (At(s.points[p]) - At(s.points[p - 1])) / dt;
      for (int j = 0; j < 6; ++j) EXPECT_LE(std::abs(v[j]), limits.max_velocity[j] * 1.001);
      if (s.kind != SegmentKind::kTransit || p + 1 == s.points.size()) continue;
      const double dt2 = s.points[p + 1].t - s.points[p].t;
      const Joints a = 2.0 * ((At(s.points[p + 1]) - At(s.points[p])) / dt2 - v) / (dt + dt2);
      for (int j = 0; j < 6; ++j) EXPECT_LE(std::abs(a[j]), limits.max_acceleration[j] * 1.001);
    }
    for (size_t p : {size_t{1}, s.points.size() - 1}) {
      const double dt = s.points[p].t - s.points[p - 1].t;
      const Joints step = (At(s.points[p]) - At(s.points[p - 1])).cwiseAbs();
      for (int j = 0; j < 6; ++j)
        EXPECT_LE(step[j], 0.5 * limits.max_acceleration[j] * dt * dt * 1.001 + 1e-12);
    }
  }
}

TEST(PlanVine, TimingStaysWithinTheJointLimits) {
  for (const bool secateur : {false, true}) {
    const RobotModel robot = DefaultUr5(secateur ? SecateurTool() : MillEndTool());
    const Stop stop = SimStop(secateur ? 1104 : 1103);
    auto result = PlanVine(stop.model, stop.plan, robot, DefaultPlatform(), Options());
    ASSERT_TRUE(result.ok()) << result.status();
    ASSERT_FALSE(result->cuts.empty());
    ExpectTimingWithinLimits(result->trajectory, robot.limits);
    // Transits were blended through their interior waypoints (a few may stop).
    const PlanStats& stats = result->stats;
    EXPECT_GT(stats.blend_vias, 0);
    EXPECT_LT(stats.blend_stops, stats.blend_vias);
  }
}

TEST(PlanVine, SecateurStopsAtTheCut) {
  const RobotModel robot = DefaultUr5(SecateurTool());
  const Stop stop = SimStop(1104);
  auto result = PlanVine(stop.model, stop.plan, robot, DefaultPlatform(), Options());
  ASSERT_TRUE(result.ok()) << result.status();
  int cuts = 0;
  for (const TrajectorySegment& s : result->trajectory.segments) {
    if (s.kind != SegmentKind::kCut) continue;
    ++cuts;
    // The configuration farthest (in joint space) from the stroke's start is the cut, where the
    // approach turns into the retract; the arm is at rest there: both neighbouring steps are no
    // longer than an acceleration from rest allows.
    size_t far = 0;
    for (size_t p = 0; p < s.points.size(); ++p)
      if ((At(s.points[p]) - At(s.points[0])).norm() > (At(s.points[far]) - At(s.points[0])).norm())
        far = p;
    ASSERT_GT(far, 0u);
    ASSERT_LT(far + 1, s.points.size());
    for (size_t p : {far, far + 1}) {
      const double dt = s.points[p].t - s.points[p - 1].t;
      const Joints step = (At(s.points[p]) - At(s.points[p - 1])).cwiseAbs();
      for (int j = 0; j < 6; ++j)
        EXPECT_LE(step[j], 0.5 * robot.limits.max_acceleration[j] * dt * dt * 1.001 + 1e-12);
    }
  }
  EXPECT_GT(cuts, 0);
}

TEST(PlanVine, NoCutsGiveAnEmptyTrajectory) {
  Stop stop = SimStop(1104);
  stop.plan.cuts.clear();
  auto result = PlanVine(stop.model, stop.plan, DefaultUr5(MillEndTool()), DefaultPlatform(),
                         Options());
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_TRUE(result->trajectory.segments.empty());
  EXPECT_TRUE(result->trajectory.unplanned.empty());
  EXPECT_EQ(result->trajectory.duration_s, 0.0);
}

TEST(PlanVine, ACutOnTheTrunkIsNotPlanned) {
  Stop stop = SimStop(1104);
  stop.plan.cuts.resize(1);
  const Cane& trunk = stop.model.canes.front();
  ASSERT_EQ(trunk.kind, CaneKind::kTrunk);
  stop.plan.cuts[0].cane_id = trunk.id;
  stop.plan.cuts[0].point = trunk.polyline.PointAt(0.5 * trunk.polyline.Length());
  auto result = PlanVine(stop.model, stop.plan, DefaultUr5(MillEndTool()), DefaultPlatform(),
                         Options());
  ASSERT_TRUE(result.ok()) << result.status();
  ASSERT_EQ(result->trajectory.unplanned.size(), 1u);
  EXPECT_EQ(result->trajectory.unplanned[0].reason, "cut_on_the_trunk");
}

TEST(PlanVine, AFarCutIsUnreachable) {
  Stop stop = SimStop(1105);
  ASSERT_FALSE(stop.plan.cuts.empty());
  // A cane 3 m along the row, beyond any reach of the arm, with a cut on it.
  Cane far;
  far.id = CaneId{999};
  far.parent_id = stop.model.canes.front().id;
  far.polyline.points = {Eigen::Vector3d(3.0, 0.8, 1.0), Eigen::Vector3d(3.3, 0.8, 1.0)};
  far.polyline.radii = {0.005, 0.004};
  stop.model.canes.push_back(far);
  Cut cut = stop.plan.cuts.front();
  cut.id = CutId{999};
  cut.cane_id = far.id;
  cut.point = Eigen::Vector3d(3.1, 0.8, 1.0);
  cut.direction = Eigen::Vector3d::UnitX();
  stop.plan.cuts.push_back(cut);
  auto result = PlanVine(stop.model, stop.plan, DefaultUr5(MillEndTool()), DefaultPlatform(),
                         Options());
  ASSERT_TRUE(result.ok()) << result.status();
  bool found = false;
  for (const UnplannedCut& u : result->trajectory.unplanned) {
    if (u.cut_id.value == 999) {
      found = true;
      EXPECT_EQ(u.reason, "unreachable");
    }
  }
  EXPECT_TRUE(found);
}

TEST(PlanVine, RejectsBadInput) {
  const RobotModel robot = DefaultUr5(MillEndTool());
  Stop stop = SimStop(1106);
  Stop nan = stop;
  nan.model.canes[1].polyline.points[0].x() = std::nan("");
  auto result = PlanVine(nan.model, nan.plan, robot, DefaultPlatform(), Options());
  EXPECT_EQ(result.status().code(), absl::StatusCode::kInvalidArgument);

  Stop unknown = stop;
  ASSERT_FALSE(unknown.plan.cuts.empty());
  unknown.plan.cuts[0].cane_id = CaneId{12345};
  result = PlanVine(unknown.model, unknown.plan, robot, DefaultPlatform(), Options());
  EXPECT_EQ(result.status().code(), absl::StatusCode::kInvalidArgument);

  PlanOptions outside = Options();
  outside.home[2] = 10.0;
  result = PlanVine(stop.model, stop.plan, robot, DefaultPlatform(), outside);
  EXPECT_EQ(result.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(result.status().message().find("options.home"), std::string::npos);
}

TEST(PlanVine, HomeInCollisionFails) {
  const RobotModel robot = DefaultUr5(MillEndTool());
  PlatformGeometry platform = DefaultPlatform();
  // A fixed sphere around the flange at home.
  const Eigen::Vector3d flange = robot.platform_from_arm_base * ForwardKinematics(DefaultHome()).translation();
  platform.fixed_spheres.push_back({flange, 0.05});
  const Stop stop = SimStop(1107);
  auto result = PlanVine(stop.model, stop.plan, robot, platform, Options());
  EXPECT_EQ(result.status().code(), absl::StatusCode::kFailedPrecondition);
}

TEST(PlanVine, AnExpiredDeadlineNeverHangs) {
  const Stop stop = SimStop(1108);
  auto result = PlanVine(stop.model, stop.plan, DefaultUr5(MillEndTool()), DefaultPlatform(),
                         Options(), Deadline::In(0.0));
  if (result.ok()) {
    EXPECT_EQ(result->cuts.size(), 0u);
    EXPECT_EQ(result->trajectory.unplanned.size(), stop.plan.cuts.size());
  } else {
    EXPECT_EQ(result.status().code(), absl::StatusCode::kDeadlineExceeded);
  }
}

TEST(PlanVine, TransitsTheMarginsCloseArePlannedWithoutThem) {
  // Margins ten times the default close most corridors between the cuts: with the fallback, a
  // transit that finds no path in the inflated scene is planned again without margins (and the
  // trajectory still touches nothing); without it, its cut is given up. (Unreached cuts are not
  // retried in a later pass here: the retry reaches some of them anyway, from elsewhere.)
  // Every query ends at a bound in work (max_tree_states, the walled-in and elbow-flip bounds),
  // never at the time limit, so the plans are the same whatever the machine's load.
  const RobotModel robot = DefaultUr5(SecateurTool());
  const PlatformGeometry platform = DefaultPlatform();
  PlanOptions fallback = Options();
  fallback.path.time_limit_s = 60.0;
  fallback.margins.max_margin_m = 0.3;
  fallback.retry_unreached = false;
  fallback.undo_walled_in = false;  // it recovers some of the same cuts another way
  PlanOptions no_fallback = fallback;
  no_fallback.margin_fallback = false;
  int planned_with = 0, planned_without = 0, solved_without_margins = 0;
  for (uint64_t seed : {1102, 1103, 1104, 1105, 1106, 1107}) {
    const Stop stop = SimStop(seed);
    auto a = PlanVine(stop.model, stop.plan, robot, platform, fallback);
    auto b = PlanVine(stop.model, stop.plan, robot, platform, no_fallback);
    ASSERT_TRUE(a.ok()) << a.status();
    ASSERT_TRUE(b.ok()) << b.status();
    planned_with += static_cast<int>(a->cuts.size());
    planned_without += static_cast<int>(b->cuts.size());
    const std::vector<PathRecord>& paths = a->stats.paths;
    for (size_t i = 0; i < paths.size(); ++i) {
      if (!paths[i].without_margins) continue;
      // Only right after the same query failed in the inflated scene.
      ASSERT_GT(i, 0u);
      EXPECT_FALSE(paths[i - 1].without_margins);
      EXPECT_EQ(paths[i - 1].outcome, PathOutcome::kNoPathWithinDeadline);
      EXPECT_EQ(paths[i - 1].to_cut, paths[i].to_cut);
      EXPECT_EQ(paths[i - 1].goals, paths[i].goals);
      solved_without_margins += paths[i].outcome == PathOutcome::kSolved;
    }
    for (const PathRecord& path : b->stats.paths) EXPECT_FALSE(path.without_margins);
    EXPECT_EQ(CountTrajectoryCollisions(a->trajectory, a->cuts, stop.model, platform, robot,
                                        CheckerKind::kPrimitives, 0.002,
                                        Options().cut_motion.cut_cane_free_radius_m),
              0)
        << "seed " << seed;
  }
  EXPECT_GT(solved_without_margins, 0);
  EXPECT_GT(planned_with, planned_without);
}

TEST(PlanVine, ACutThatWallsTheArmInIsUndone) {
  // Margins ten times the default and no fallback wall the arm in at some cuts: transits from
  // there fail. Such a cut is undone and tried again later; every cut still ends planned once or
  // unplanned once, and the trajectory touches nothing.
  const RobotModel robot = DefaultUr5(SecateurTool());
  const PlatformGeometry platform = DefaultPlatform();
  PlanOptions undo = Options();
  undo.margins.max_margin_m = 0.3;
  undo.margin_fallback = false;
  int undone = 0;
  for (uint64_t seed : {1102, 1108}) {
    const Stop stop = SimStop(seed);
    auto a = PlanVine(stop.model, stop.plan, robot, platform, undo);
    ASSERT_TRUE(a.ok()) << a.status();
    undone += a->stats.walled_in_undone;
    std::set<int> ids;
    for (const Cut& cut : a->cuts) EXPECT_TRUE(ids.insert(cut.id.value).second);
    for (const UnplannedCut& u : a->trajectory.unplanned)
      EXPECT_TRUE(ids.insert(u.cut_id.value).second) << "cut " << u.cut_id.value;
    EXPECT_EQ(ids.size(), stop.plan.cuts.size());
    EXPECT_EQ(a->trajectory.segments.size(), 2 * a->cuts.size() + (a->cuts.empty() ? 0 : 1));
    EXPECT_EQ(CountTrajectoryCollisions(a->trajectory, a->cuts, stop.model, platform, robot,
                                        CheckerKind::kPrimitives, 0.002,
                                        Options().cut_motion.cut_cane_free_radius_m),
              0)
        << "seed " << seed;
  }
  EXPECT_GT(undone, 0);
}

// Whether `cut` has no collision-free motion in `scene` with `square` (no slide) but has one
// with `sliding`: a cut only a slide frees.
bool OnlyASlideFrees(const RobotModel& robot, const Stop& stop, const CollisionScene& scene,
                     const Cut& cut, const CutMotionOptions& square,
                     const CutMotionOptions& sliding) {
  const std::span<const Cut> one(&cut, 1);
  return PlanCutMotions(robot, stop.model, scene, one, square, Deadline::Infinite())[0].outcome ==
             CutMotionOutcome::kNoCollisionFreeMotion &&
         PlanCutMotions(robot, stop.model, scene, one, sliding, Deadline::Infinite())[0]
                 .outcome == CutMotionOutcome::kPlanned;
}

// A cut that no motion frees without sliding, alone in its plan: its only pass plans no motion,
// so with last_resort_max_slide_m it is searched again, sliding, and made; without, given up.
TEST(PlanVine, ACutThatNoPassFreesSlidesFurtherAsALastResort) {
  const RobotModel robot = DefaultUr5(SecateurTool());
  const PlatformGeometry platform = DefaultPlatform();
  PlanOptions options = Options();
  options.cut_motion.max_slide_m = 0;
  CutMotionOptions sliding = options.cut_motion;
  sliding.max_slide_m = 0.10;
  for (uint64_t seed : {1100, 1101, 1102, 1103}) {
    const Stop stop = SimStop(seed);
    const auto scene = CollisionScene::Build(stop.model, platform, robot);
    ASSERT_TRUE(scene.ok()) << scene.status();
    for (const Cut& cut : stop.plan.cuts) {
      if (!OnlyASlideFrees(robot, stop, *scene, cut, options.cut_motion, sliding)) continue;
      CutPlan plan = stop.plan;
      plan.cuts = {cut};
      options.last_resort_max_slide_m = 0.10;
      auto result = PlanVine(stop.model, plan, robot, platform, options);
      ASSERT_TRUE(result.ok()) << result.status();
      for (const UnplannedCut& u : result->trajectory.unplanned)
        EXPECT_NE(u.reason, "no_collision_free_cut_motion") << "seed " << seed;
      if (result->cuts.empty()) continue;  // no path to it: try another cut
      EXPECT_GT((result->cuts[0].point - cut.point).norm(), 0.005) << "seed " << seed;
      EXPECT_FALSE(result->stats.notes.empty());
      options.last_resort_max_slide_m = 0;
      result = PlanVine(stop.model, plan, robot, platform, options);
      ASSERT_TRUE(result.ok()) << result.status();
      ASSERT_EQ(result->trajectory.unplanned.size(), 1u);
      EXPECT_EQ(result->trajectory.unplanned[0].reason, "no_collision_free_cut_motion");
      return;
    }
  }
  FAIL() << "no cut on seeds 1100-1103 needs a slide and is reached";
}

// A pass that plans motions but whose paths reach none of them makes no cut either: its blocked
// cuts still get the last resort. With no path possible (RRT-Connect given no time, no direct
// segments), a cut that needs a slide ends with no path once the last resort gave it a motion,
// and with no collision-free motion without the last resort.
TEST(PlanVine, APassThatReachesNoMotionStillGivesItsBlockedCutsTheLastResort) {
  const RobotModel robot = DefaultUr5(SecateurTool());
  const PlatformGeometry platform = DefaultPlatform();
  PlanOptions options = Options();
  options.cut_motion.max_slide_m = 0;
  options.path.try_direct_first = false;
  options.path.time_limit_s = 1e-9;
  CutMotionOptions sliding = options.cut_motion;
  sliding.max_slide_m = 0.10;
  for (uint64_t seed : {1100, 1101, 1102, 1103}) {
    const Stop stop = SimStop(seed);
    const auto scene = CollisionScene::Build(stop.model, platform, robot);
    ASSERT_TRUE(scene.ok()) << scene.status();
    const std::vector<CutMotion> square = PlanCutMotions(robot, stop.model, *scene, stop.plan.cuts,
                                                         options.cut_motion, Deadline::Infinite());
    const auto free_at =
        std::find_if(square.begin(), square.end(), [](const CutMotion& m) {
          return m.outcome == CutMotionOutcome::kPlanned;
        });
    if (free_at == square.end()) continue;
    for (size_t k = 0; k < square.size(); ++k) {
      if (!OnlyASlideFrees(robot, stop, *scene, stop.plan.cuts[k], options.cut_motion, sliding))
        continue;
      CutPlan plan = stop.plan;
      plan.cuts = {stop.plan.cuts[free_at - square.begin()], stop.plan.cuts[k]};
      auto reason_of_blocked = [&](double last_resort_m) {
        options.last_resort_max_slide_m = last_resort_m;
        auto result = PlanVine(stop.model, plan, robot, platform, options);
        EXPECT_TRUE(result.ok()) << result.status();
        if (!result.ok()) return std::string();
        EXPECT_TRUE(result->cuts.empty());
        for (const UnplannedCut& u : result->trajectory.unplanned)
          if (u.cut_id.value == plan.cuts[1].id.value) return u.reason;
        return std::string("planned");
      };
      EXPECT_EQ(reason_of_blocked(0.10), "no_path_within_deadline") << "seed " << seed;
      EXPECT_EQ(reason_of_blocked(0.0), "no_collision_free_cut_motion") << "seed " << seed;
      return;
    }
  }
  FAIL() << "no stop of seeds 1100-1103 has a free cut and a cut that needs a slide";
}

TEST(PlanVine, RejectsANegativeLastResortSlide) {
  PlanOptions options = Options();
  options.last_resort_max_slide_m = -0.1;
  const absl::Status status = options.Validate();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("last_resort_max_slide_m"), std::string::npos);
}

TEST(PlanVine, EveryTransitIsProvenFreeOfTheVineAsItIsThen) {
  // Stronger than the sampled re-check: each transit, between its samples, is proven free
  // (MotionProver) of the vine after the cuts before it -- stubs included, margins not.
  const RobotModel robot = DefaultUr5(SecateurTool());
  const PlatformGeometry platform = DefaultPlatform();
  int transits = 0;
  for (uint64_t seed : {1100, 1103}) {
    const Stop stop = SimStop(seed);
    auto result = PlanVine(stop.model, stop.plan, robot, platform, Options());
    ASSERT_TRUE(result.ok()) << result.status();
    std::vector<Cut> made;
    for (const TrajectorySegment& segment : result->trajectory.segments) {
      if (segment.kind == SegmentKind::kCut) {
        for (const Cut& c : result->cuts)
          if (c.id.value == segment.cut_id.value) made.push_back(c);
        continue;
      }
      auto scene = CollisionScene::Build(WithoutFallenWood(stop.model, made), platform, robot);
      ASSERT_TRUE(scene.ok()) << scene.status();
      MotionProver prover(*scene, [&](const CollisionScene& s) {
        return MakeChecker(CheckerKind::kPrimitives, robot, s);
      });
      std::vector<Joints> samples;
      for (const TrajectoryPoint& p : segment.points) samples.push_back(At(p));
      EXPECT_TRUE(prover.IsPathFree(samples)) << "seed " << seed << " after " << made.size();
      ++transits;
    }
  }
  EXPECT_GT(transits, 10);
}

}  // namespace
}  // namespace vb::plan
