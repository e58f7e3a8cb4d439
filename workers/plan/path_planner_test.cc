// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/path_planner.h"

#include <cmath>
#include <atomic>
#include <chrono>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "gtest/gtest.h"
#include "sim/vine_generator.h"
#include "workers/plan/collision_scene.h"
#include "workers/plan/fake_checker_test_util.h"
#include "workers/plan/path_planner_test_util.h"
#include "workers/plan/path_shortcut.h"
#include "workers/plan/robot_model.h"
#include "workers/plan/simple_tool_test_util.h"
#include "workers/plan/time_parameterization.h"

namespace vb::plan {
namespace {

using testing::ExpectValidPath;
using testing::JointBallChecker;

using testing::J;

TEST(PathPlanner, StraightLineWhenFree) {
  JointBallChecker checker;
  checker.AddBall(J(0, 3), 0.5);
  const PathResult r = PlanPath(checker, JointLimits(), J(-1), J(1), PathOptions(), Deadline::Infinite());
  ExpectValidPath(checker, JointLimits(), r, J(-1), J(1));
  EXPECT_TRUE(r.direct);
  EXPECT_EQ(r.waypoints.size(), 2u);
  EXPECT_GT(r.checks, 0);
}

TEST(PathPlanner, GoesAroundAJointSpaceObstacle) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  const JointLimits limits;
  const Joints start = J(-2, 0.1), goal = J(2, -0.1, 0.2);
  const PathResult r = PlanPath(checker, limits, start, goal, PathOptions(), Deadline::Infinite());
  ExpectValidPath(checker, limits, r, start, goal);
  EXPECT_FALSE(r.direct);
  EXPECT_GE(r.waypoints.size(), 3u);
  // Shortcutting brings the path near the shortest way round (two tangents and an arc: ~4.5 rad
  // of joint-space length for this geometry); RRT-Connect alone wanders far more.
  double length = 0;
  for (size_t k = 1; k < r.waypoints.size(); ++k) length += (r.waypoints[k] - r.waypoints[k - 1]).norm();
  EXPECT_LT(length, 6.0);
}

TEST(PathPlanner, ShortcuttingNeverSlowsThePath) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  checker.AddBall(J(1.5, 1.0), 0.6);
  const JointLimits limits;
  PathOptions raw;
  raw.shortcut_rounds = 0;
  PathOptions shortcut = raw;
  shortcut.shortcut_rounds = 100;
  const Joints start = J(-2, 0.2), goal = J(2.5, 0.5, 0.3);
  const PathResult a = PlanPath(checker, limits, start, goal, raw, Deadline::Infinite());
  const PathResult b = PlanPath(checker, limits, start, goal, shortcut, Deadline::Infinite());
  ExpectValidPath(checker, limits, a, start, goal);
  ExpectValidPath(checker, limits, b, start, goal);
  EXPECT_LE(PathTimeS(b.waypoints, limits), PathTimeS(a.waypoints, limits) + 1e-9);
}

TEST(PathPlanner, SameSeedSamePath) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  PathOptions options;
  options.seed = 7;
  const Joints start = J(-2, 0.1), goal = J(2, -0.1, 0.2);
  PathPlanner planner(checker, JointLimits(), options);
  const PathResult a = planner.Plan(start, goal, Deadline::Infinite());
  // Another planner in between must not change the next result (no shared RNG state).
  PathOptions other = options;
  other.seed = 99;
  (void)PlanPath(checker, JointLimits(), start, goal, other, Deadline::Infinite());
  const PathResult b = planner.Plan(start, goal, Deadline::Infinite());
  const PathResult c = PlanPath(checker, JointLimits(), start, goal, options, Deadline::Infinite());
  ASSERT_EQ(a.outcome, PathOutcome::kSolved);
  EXPECT_EQ(a.waypoints, b.waypoints);
  EXPECT_EQ(a.waypoints, c.waypoints);
}

TEST(PathPlanner, ReusedPlannerSolvesManyQueries) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  const JointLimits limits;
  PathPlanner planner(checker, limits, PathOptions());
  for (int k = 0; k < 20; ++k) {
    const double s = 0.1 * k;
    const Joints start = J(-2, s - 1.0, 0.1), goal = J(2, 1.0 - s, -0.2, 0.3);
    const PathResult r = planner.Plan(start, goal, Deadline::Infinite());
    ExpectValidPath(checker, limits, r, start, goal);
  }
}

TEST(PathPlanner, DirectDisabledStillFindsAPath) {
  JointBallChecker checker;
  PathOptions options;
  options.try_direct_first = false;
  const PathResult r = PlanPath(checker, JointLimits(), J(-1), J(1, 1), options, Deadline::Infinite());
  ExpectValidPath(checker, JointLimits(), r, J(-1), J(1, 1));
  EXPECT_FALSE(r.direct);
  EXPECT_EQ(r.waypoints.size(), 2u);  // shortcutting finds the straight line
}

TEST(PathPlanner, StartInCollisionFails) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  const PathResult r = PlanPath(checker, JointLimits(), J(0.5), J(2), PathOptions(), Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kStartInCollision);
  EXPECT_TRUE(r.waypoints.empty());
  EXPECT_EQ(PathOutcomeName(r.outcome), "start_in_collision");
}

TEST(PathPlanner, GoalInCollisionFails) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  const PathResult r = PlanPath(checker, JointLimits(), J(2), J(0.5), PathOptions(), Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kGoalInCollision);
}

TEST(PathPlanner, EnclosedGoalFailsWithinTheDeadline) {
  JointBallChecker checker;
  checker.AddShell(J(2), 0.5, 0.8);  // the goal at the centre is free, but walled in
  PathOptions options;
  options.time_limit_s = 30.0;  // the deadline, not the time limit, must stop it
  const auto t0 = std::chrono::steady_clock::now();
  const PathResult r = PlanPath(checker, JointLimits(), J(-2), J(2), options, Deadline::In(0.2));
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.outcome, PathOutcome::kNoPathWithinDeadline) << r.message;
  EXPECT_TRUE(r.waypoints.empty());
  EXPECT_LT(elapsed, 10.0);  // generous: a hang, not speed, is what this catches
}

TEST(PathPlanner, EnclosedGoalFailsWithinTheTimeLimit) {
  JointBallChecker checker;
  checker.AddShell(J(2), 0.5, 0.8);
  PathOptions options;
  options.time_limit_s = 0.1;
  const PathResult r = PlanPath(checker, JointLimits(), J(-2), J(2), options, Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_LT(r.planning_s, 10.0);
}

TEST(PathPlanner, TreeStateBoundStopsAnEnclosedGoal) {
  JointBallChecker checker;
  checker.AddShell(J(2), 0.5, 0.8);
  PathOptions options;
  options.time_limit_s = 60.0;  // the bound on states, not the time limit, must stop it
  options.max_tree_states = 300;
  const PathResult r = PlanPath(checker, JointLimits(), J(-2), J(2), options, Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kNoPathWithinDeadline) << r.message;
  EXPECT_LT(r.planning_s, 30.0);  // generous: reaching the time limit is what this catches
  // The same query stops at the same work: a bound in states, not time, is reproducible.
  const PathResult again = PlanPath(checker, JointLimits(), J(-2), J(2), options, Deadline::Infinite());
  EXPECT_EQ(again.checks, r.checks);
  // A reachable goal behind an obstacle is still found within the bound.
  JointBallChecker ball;
  ball.AddBall(J(0), 1.0);
  const PathResult ok = PlanPath(ball, JointLimits(), J(-2, 0.1), J(2, -0.1), options, Deadline::Infinite());
  ExpectValidPath(ball, JointLimits(), ok, J(-2, 0.1), J(2, -0.1));
}

TEST(PathPlanner, CancelledDeadlineStopsAtOnce) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  std::atomic<bool> cancelled{true};
  const PathResult r = PlanPath(checker, JointLimits(), J(-2), J(2), PathOptions(),
                                Deadline::In(100.0, &cancelled));
  EXPECT_EQ(r.outcome, PathOutcome::kNoPathWithinDeadline);
}

TEST(PathPlanner, NonFiniteInputIsRejected) {
  JointBallChecker checker;
  Joints bad = J(0);
  bad[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(PlanPath(checker, JointLimits(), bad, J(1), PathOptions(), Deadline::Infinite()).outcome,
            PathOutcome::kInvalidInput);
  const PathResult r = PlanPath(checker, JointLimits(), J(1), bad, PathOptions(), Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kInvalidInput);
  EXPECT_NE(r.message.find("goal"), std::string::npos);
  bad[3] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(PlanPath(checker, JointLimits(), bad, J(1), PathOptions(), Deadline::Infinite()).outcome,
            PathOutcome::kInvalidInput);
}

TEST(PathPlanner, OutsideLimitsIsRejected) {
  JointBallChecker checker;
  JointLimits limits;
  limits.upper[1] = 1.0;
  const PathResult r = PlanPath(checker, limits, J(0), J(0, 1.5), PathOptions(), Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kOutsideLimits);
  EXPECT_NE(r.message.find("goal"), std::string::npos);
}

TEST(PathPlanner, BadOptionsAndLimitsAreRejected) {
  JointBallChecker checker;
  PathOptions options;
  options.max_step_m = 0.0;
  EXPECT_NE(options.Validate().message().find("max_step_m"), std::string::npos);
  PathResult r = PlanPath(checker, JointLimits(), J(0), J(1), options, Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kInvalidInput);
  options = PathOptions();
  options.time_limit_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(options.Validate().ok());
  options = PathOptions();
  options.shortcut_rounds = -1;
  EXPECT_FALSE(options.Validate().ok());
  options = PathOptions();
  options.max_tree_states = -1;
  EXPECT_NE(options.Validate().message().find("max_tree_states"), std::string::npos);
  JointLimits limits;
  limits.max_velocity[2] = -1;
  r = PlanPath(checker, limits, J(0), J(1), PathOptions(), Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kInvalidInput);
}

TEST(PathPlanner, StartEqualsGoal) {
  JointBallChecker checker;
  const PathResult r = PlanPath(checker, JointLimits(), J(0.3), J(0.3), PathOptions(), Deadline::Infinite());
  ASSERT_EQ(r.outcome, PathOutcome::kSolved);
  EXPECT_EQ(r.waypoints.size(), 2u);
}

// Balls checked pointwise; motions by the base class's sampling (CollisionChecker::IsMotionFree
// and MotionSteps), as the real checkers do.
class SampledBallChecker : public CollisionChecker {
 public:
  explicit SampledBallChecker(std::vector<std::pair<Joints, double>> balls) : balls_(std::move(balls)) {}
  bool IsFree(const Joints& q) override {
    ++checks_;
    for (const auto& [c, r] : balls_) {
      if ((q - c).norm() < r) return false;
    }
    return true;
  }
  double Clearance(const Joints& q) override {
    ++checks_;
    double best = 1e9;
    for (const auto& [c, r] : balls_) best = std::min(best, (q - c).norm() - r);
    return best;
  }

 private:
  std::vector<std::pair<Joints, double>> balls_;
};

// A SampledBallChecker that records the segments found free, with their resolution.
class RecordingBallChecker : public SampledBallChecker {
 public:
  using SampledBallChecker::SampledBallChecker;
  bool IsMotionFree(const Joints& a, const Joints& b, double max_step_m) override {
    const bool free = SampledBallChecker::IsMotionFree(a, b, max_step_m);
    if (free) passed_.push_back({a, b, max_step_m});
    return free;
  }
  // Whether a -> b (either way) was found free at a resolution of at most step_m (exactly
  // step_m when `exactly`).
  bool Passed(const Joints& a, const Joints& b, double step_m, bool exactly = false) const {
    for (const Segment& s : passed_) {
      const bool step = exactly ? s.step_m == step_m : s.step_m <= step_m;
      if (step && ((s.a == a && s.b == b) || (s.a == b && s.b == a))) return true;
    }
    return false;
  }

 private:
  struct Segment {
    Joints a, b;
    double step_m;
  };
  std::vector<Segment> passed_;
};

TEST(PathPlanner, EverySegmentPassesASampledChecker) {
  SampledBallChecker checker({{J(0), 1.0}, {J(1.5, 1.2), 0.5}, {J(-1, -1, 1), 0.7}});
  const JointLimits limits;
  PathPlanner planner(checker, limits, PathOptions());
  for (int k = 0; k < 10; ++k) {
    const Joints start = J(-2, 0.1 * k), goal = J(2, -0.1 * k, 0.3);
    const PathResult r = planner.Plan(start, goal, Deadline::Infinite());
    ASSERT_EQ(r.outcome, PathOutcome::kSolved) << r.message;
    EXPECT_FALSE(r.direct);
    for (size_t i = 1; i < r.waypoints.size(); ++i) {
      EXPECT_TRUE(checker.IsMotionFree(r.waypoints[i - 1], r.waypoints[i], 0.01)) << k << " " << i;
    }
  }
}

// The primitive checker on a simulated vine (tuning seed): paths between random free
// configurations near a working pose are found, and every segment passes the checker.
TEST(PathPlanner, PlansOnASimulatedVineScene) {
  sim::VineGeneratorOptions vine_options;
  vine_options.neighbours = false;
  auto sim_scene = sim::GenerateScene(1100, 0, vine_options);
  ASSERT_TRUE(sim_scene.ok()) << sim_scene.status();
  const RobotModel robot = DefaultUr5(SimpleMillEnd());
  auto scene = CollisionScene::Build(sim_scene->vine, DefaultPlatform(), robot);
  ASSERT_TRUE(scene.ok()) << scene.status();
  std::unique_ptr<CollisionChecker> checker = MakePrimitiveChecker(robot, *scene);
  std::mt19937 rng(1100);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  Joints working;
  working << 0.0, -1.57, 1.2, -1.2, -1.57, 0.0;
  auto random_free = [&] {
    for (int tries = 0; tries < 10000; ++tries) {
      Joints q = working;
      for (int i = 0; i < 6; ++i) q[i] += u(rng);
      if (robot.limits.Contains(q) && checker->IsFree(q)) return q;
    }
    ADD_FAILURE() << "no free configuration";
    return working;
  };
  PathPlanner planner(*checker, robot.limits, PathOptions());
  int solved = 0;
  for (int k = 0; k < 10; ++k) {
    const Joints a = random_free(), b = random_free();
    const PathResult r = planner.Plan(a, b, Deadline::In(5.0));
    if (r.outcome != PathOutcome::kSolved) continue;
    ++solved;
    EXPECT_EQ(r.waypoints.front(), a);
    EXPECT_EQ(r.waypoints.back(), b);
    for (size_t i = 1; i < r.waypoints.size(); ++i) {
      EXPECT_TRUE(checker->IsMotionFree(r.waypoints[i - 1], r.waypoints[i], 0.01)) << k << " " << i;
    }
  }
  EXPECT_GE(solved, 8);
}

TEST(ShortcutPath, RemovesADetourAndChecksEverySegment) {
  JointBallChecker checker;
  checker.AddBall(J(0, 3), 0.5);  // nowhere near
  std::vector<Joints> w = {J(-1), J(-0.5, 1.0), J(0, -1.0), J(0.5, 1.0), J(1)};
  const int taken = ShortcutPath(checker, JointLimits(), 0.01, 20, 3, Deadline::Infinite(), w);
  EXPECT_GE(taken, 1);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w.front(), J(-1));
  EXPECT_EQ(w.back(), J(1));
}

TEST(ShortcutPath, KeepsAPathThatCannotBeShortened) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  // Around the ball by its tangent corners: any shortcut between segments cuts into it.
  std::vector<Joints> w = {J(-2), J(-1.0, 1.2), J(1.0, 1.2), J(2)};
  ASSERT_TRUE(checker.IsMotionFree(w[0], w[1], 0.01) && checker.IsMotionFree(w[1], w[2], 0.01) &&
              checker.IsMotionFree(w[2], w[3], 0.01));
  const double before = PathTimeS(w, JointLimits());
  ShortcutPath(checker, JointLimits(), 0.01, 50, 1, Deadline::Infinite(), w);
  for (size_t k = 1; k < w.size(); ++k) EXPECT_TRUE(checker.IsMotionFree(w[k - 1], w[k], 0.01));
  EXPECT_LE(PathTimeS(w, JointLimits()), before + 1e-12);
  EXPECT_GE(w.size(), 3u);
}

TEST(PlanToAny, TakesTheFirstFreeStraightSegment) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  PathPlanner planner(checker, JointLimits(), PathOptions());
  const Joints start = J(-2);
  const std::vector<Joints> goals = {J(2), J(-2, 1.5), J(-2, -1.5)};  // the first is behind the ball
  const PathResult r = planner.PlanToAny(start, goals, Deadline::Infinite());
  ExpectValidPath(checker, JointLimits(), r, start, goals[1]);
  EXPECT_TRUE(r.direct);
  EXPECT_EQ(r.goal_index, 1);
}

TEST(PlanToAny, ReachesAFreeGoalWhenTheFirstIsWalledIn) {
  // RRT-Connect adds OMPL goal states one at a time as its goal tree grows; a walled-in first
  // goal never grows it, so the second goal must be a root from the start (reversed roles).
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  checker.AddShell(J(2.5, 2.5), 0.3, 0.6);
  PathOptions options;
  options.time_limit_s = 5.0;
  PathPlanner planner(checker, JointLimits(), options);
  const Joints start = J(-2, 0.1);
  const std::vector<Joints> goals = {J(2.5, 2.5), J(2, -0.1, 0.2)};
  const PathResult r = planner.PlanToAny(start, goals, Deadline::Infinite());
  ExpectValidPath(checker, JointLimits(), r, start, goals[1]);
  EXPECT_FALSE(r.direct);
  EXPECT_EQ(r.goal_index, 1);
  // The same query with the goals swapped reaches the same goal, and Plan() to the walled-in
  // goal alone fails.
  const std::vector<Joints> swapped = {goals[1], goals[0]};
  const PathResult s = planner.PlanToAny(start, swapped, Deadline::Infinite());
  ASSERT_EQ(s.outcome, PathOutcome::kSolved) << s.message;
  EXPECT_EQ(s.goal_index, 0);
  PathOptions short_limit = options;
  short_limit.time_limit_s = 0.1;
  PathPlanner short_planner(checker, JointLimits(), short_limit);
  EXPECT_EQ(short_planner.Plan(start, goals[0], Deadline::Infinite()).outcome,
            PathOutcome::kNoPathWithinDeadline);
}

TEST(PlanToAny, SameSeedSamePath) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  checker.AddBall(J(0, 2), 0.8);
  PathPlanner planner(checker, JointLimits(), PathOptions());
  const Joints start = J(-2, 0.3);
  const std::vector<Joints> goals = {J(2, -0.3, 0.1), J(2, 0.5, -0.2), J(1.8, 0.2, 0.4)};
  const PathResult a = planner.PlanToAny(start, goals, Deadline::Infinite());
  const PathResult b = planner.PlanToAny(start, goals, Deadline::Infinite());
  ASSERT_EQ(a.outcome, PathOutcome::kSolved) << a.message;
  EXPECT_FALSE(a.direct);
  EXPECT_EQ(a.waypoints, b.waypoints);
  EXPECT_EQ(a.goal_index, b.goal_index);
  ExpectValidPath(checker, JointLimits(), a, start, goals[a.goal_index]);
}

TEST(PlanToAny, EnclosedGoalsFailInOneTimeLimit) {
  JointBallChecker checker;
  checker.AddShell(J(2), 0.3, 0.6);
  checker.AddShell(J(-2, 2), 0.3, 0.6);
  PathOptions options;
  options.time_limit_s = 0.2;
  PathPlanner planner(checker, JointLimits(), options);
  const std::vector<Joints> goals = {J(2), J(-2, 2)};
  const PathResult r = planner.PlanToAny(J(0, -2), goals, Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kNoPathWithinDeadline) << r.message;
  EXPECT_EQ(r.goal_index, -1);
  EXPECT_TRUE(r.waypoints.empty());
  EXPECT_LT(r.planning_s, 10.0);  // generous: a hang, not speed, is what this catches
}

TEST(PlanToAny, SkipsGoalsInCollisionOrOutsideTheLimits) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  PathPlanner planner(checker, JointLimits(), PathOptions());
  const Joints start = J(-2);
  const Joints in_collision = J(0.5), outside = J(10), free = J(-2, 1);
  const std::vector<Joints> goals = {in_collision, outside, free};
  const PathResult r = planner.PlanToAny(start, goals, Deadline::Infinite());
  ExpectValidPath(checker, JointLimits(), r, start, free);
  EXPECT_EQ(r.goal_index, 2);
  // None usable: the first goal's outcome names it.
  const std::vector<Joints> bad_first = {in_collision, outside};
  const PathResult a = planner.PlanToAny(start, bad_first, Deadline::Infinite());
  EXPECT_EQ(a.outcome, PathOutcome::kGoalInCollision);
  EXPECT_NE(a.message.find("goals[0]"), std::string::npos) << a.message;
  const std::vector<Joints> outside_first = {outside, in_collision};
  EXPECT_EQ(planner.PlanToAny(start, outside_first, Deadline::Infinite()).outcome,
            PathOutcome::kOutsideLimits);
}

TEST(PlanToAny, RejectsNoGoalsAndNonFiniteGoals) {
  JointBallChecker checker;
  PathPlanner planner(checker, JointLimits(), PathOptions());
  const PathResult empty = planner.PlanToAny(J(0), {}, Deadline::Infinite());
  EXPECT_EQ(empty.outcome, PathOutcome::kInvalidInput);
  EXPECT_NE(empty.message.find("goals"), std::string::npos);
  Joints bad = J(1);
  bad[3] = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Joints> goals = {J(1), bad};
  const PathResult r = planner.PlanToAny(J(0), goals, Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kInvalidInput);
  EXPECT_NE(r.message.find("goals[1]"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace vb::plan

namespace vb::plan {
namespace {

// Thin balls that RRT-Connect's coarse edge checks (tree_max_step_m) step over: the paths found
// that way are checked at max_step_m, and a query whose path collides there is planned again with
// fine edge checks; so every returned segment passes the checker at max_step_m.
TEST(PathPlanner, CoarseTreeEdgesStillGiveSegmentsFreeAtMaxStep) {
  std::vector<std::pair<Joints, double>> balls = {{J(0), 1.0}};  // no straight path
  std::mt19937 rng(1101);
  std::uniform_real_distribution<double> u(-2.5, 2.5);
  for (int k = 0; k < 3000; ++k) balls.push_back({J(u(rng), u(rng), u(rng)), 0.1});
  RecordingBallChecker checker(balls);
  PathOptions options;
  options.tree_max_step_m = 2.0;  // ~1.7 rad of one joint between edge checks
  options.shortcut_rounds = 0;
  const JointLimits limits;
  PathPlanner planner(checker, limits, options);
  int solved = 0;
  for (int k = 0; k < 20; ++k) {
    const Joints start = J(-2, 0.1 * k - 1, 0.2), goal = J(2, 1 - 0.1 * k, -0.2);
    if (!checker.IsFree(start) || !checker.IsFree(goal)) continue;
    const PathResult r = planner.Plan(start, goal, Deadline::In(10.0));
    if (r.outcome != PathOutcome::kSolved) continue;
    ++solved;
    for (size_t i = 1; i < r.waypoints.size(); ++i) {
      const Joints& a = r.waypoints[i - 1];
      const Joints& b = r.waypoints[i];
      EXPECT_TRUE(checker.IsMotionFree(a, b, options.max_step_m)) << k << " " << i;
      // The planner itself checked it at max_step_m.
      EXPECT_TRUE(checker.Passed(a, b, options.max_step_m)) << k << " " << i;
    }
  }
  EXPECT_GE(solved, 10);
}

TEST(PathPlanner, TreeEdgesKeptByShortcuttingAreCheckedAtMaxStep) {
  // One ball, no thin ones: greedy skipping cannot straighten a path around it entirely, so
  // some returned segments are RRT-Connect's own edges (checked at tree_max_step_m); each must
  // also have been checked at max_step_m.
  RecordingBallChecker checker({{J(0), 1.0}});
  PathOptions options;
  options.tree_max_step_m = 0.5;
  options.shortcut_rounds = 0;
  const JointLimits limits;
  PathPlanner planner(checker, limits, options);
  int tree_segments = 0;
  for (int k = 0; k < 20; ++k) {
    const Joints start = J(-1.5, 0.05 * k - 0.5, 0.2), goal = J(1.5, 0.5 - 0.05 * k, -0.2);
    const PathResult r = planner.Plan(start, goal, Deadline::In(10.0));
    ASSERT_EQ(r.outcome, PathOutcome::kSolved) << r.message;
    for (size_t i = 1; i < r.waypoints.size(); ++i) {
      const Joints& a = r.waypoints[i - 1];
      const Joints& b = r.waypoints[i];
      EXPECT_TRUE(checker.Passed(a, b, options.max_step_m)) << k << " " << i;
      if (checker.Passed(a, b, options.tree_max_step_m, /*exactly=*/true)) ++tree_segments;
    }
  }
  EXPECT_GT(tree_segments, 0);
}

TEST(PathPlanner, NegativeTreeStepIsRejected) {
  PathOptions options;
  options.tree_max_step_m = -0.01;
  EXPECT_NE(options.Validate().message().find("tree_max_step_m"), std::string::npos);
}

// remember_failures: the pocket around J(2) is walled in by a shell; the start region is outside.
}  // namespace
}  // namespace vb::plan
