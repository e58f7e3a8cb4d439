// SPDX-License-Identifier: Apache-2.0
// The path planner's refusals: queries it gives up on before RRT-Connect's bound on states
// (remembered failures, walled-in goals, elbow flips). path_planner_test.cc tests the rest.
#include "workers/plan/path_planner.h"

#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "gtest/gtest.h"
#include "workers/plan/fake_checker_test_util.h"
#include "workers/plan/path_planner_test_util.h"

namespace vb::plan {
namespace {

using testing::ExpectValidPath;
using testing::J;
using testing::JointBallChecker;

PathOptions RememberingOptions() {
  PathOptions options;
  options.time_limit_s = 60.0;  // the bound on states, not time, stops the failed queries
  options.max_tree_states = 300;
  options.remember_failures = true;
  return options;
}

TEST(RememberFailures, RepeatedHopelessQueryFailsAtOnce) {
  JointBallChecker checker;
  checker.AddShell(J(2), 0.5, 0.8);
  PathPlanner planner(checker, JointLimits(), RememberingOptions());
  const PathResult first = planner.Plan(J(-2), J(2), Deadline::Infinite());
  ASSERT_EQ(first.outcome, PathOutcome::kNoPathWithinDeadline) << first.message;
  EXPECT_FALSE(first.repeated_failure);
  EXPECT_EQ(planner.remembered_failures(), 1);
  // From another start in the same region, to another goal in the same pocket and to the first
  // goal among both: each fails before RRT-Connect, for a fraction of the first query's checks.
  const std::vector<Joints> goals = {J(2, 0.2), J(2)};
  const PathResult again = planner.PlanToAny(J(-2.3, 0.4), goals, Deadline::Infinite());
  EXPECT_EQ(again.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_TRUE(again.repeated_failure);
  EXPECT_TRUE(again.waypoints.empty());
  EXPECT_NE(again.message.find("like failed query 0"), std::string::npos) << again.message;
  EXPECT_LT(again.checks * 10, first.checks);
  EXPECT_EQ(planner.remembered_failures(), 1);  // a refused query adds nothing
  // Forgotten, the same query runs RRT-Connect again (and fails, and is remembered again).
  planner.ForgetFailures();
  EXPECT_EQ(planner.remembered_failures(), 0);
  const PathResult fresh = planner.PlanToAny(J(-2.3, 0.4), goals, Deadline::Infinite());
  EXPECT_EQ(fresh.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_FALSE(fresh.repeated_failure);
  EXPECT_GT(fresh.checks, 10 * again.checks);
  EXPECT_EQ(planner.remembered_failures(), 1);
}

TEST(RememberFailures, ReachableQueriesAreStillPlanned) {
  JointBallChecker checker;
  checker.AddShell(J(2), 0.5, 0.8);
  checker.AddBall(J(-0.5, 2), 0.7);
  const JointLimits limits;
  PathPlanner planner(checker, limits, RememberingOptions());
  ASSERT_EQ(planner.Plan(J(-2), J(2), Deadline::Infinite()).outcome,
            PathOutcome::kNoPathWithinDeadline);
  ASSERT_EQ(planner.remembered_failures(), 1);
  // A goal outside the pocket behind a ball (RRT-Connect needed): a valid path.
  const Joints start = J(-2, 2.1), goal = J(1, 2, 0.1);
  ASSERT_FALSE(checker.IsMotionFree(start, goal, 0.01));
  const PathResult r = planner.Plan(start, goal, Deadline::Infinite());
  ExpectValidPath(checker, limits, r, start, goal);
  EXPECT_FALSE(r.repeated_failure);
  // Goals of which one lies outside the failed query's pocket: the query runs and reaches it.
  const std::vector<Joints> goals = {J(2), goal};
  const PathResult any = planner.PlanToAny(start, goals, Deadline::Infinite());
  ASSERT_EQ(any.outcome, PathOutcome::kSolved) << any.message;
  EXPECT_EQ(any.goal_index, 1);
  ExpectValidPath(checker, limits, any, start, goal);
}

TEST(RememberFailures, AStartTheFailedTreesDoNotJoinIsNotRefused) {
  JointBallChecker checker;
  checker.AddShell(J(2), 0.5, 0.8);
  // A second, larger pocket around the second start (its tree fills the bound on states).
  checker.AddShell(J(-4, 0, 3), 2.0, 2.3);
  PathOptions options = RememberingOptions();
  options.max_tree_states = 60;
  PathPlanner planner(checker, JointLimits(), options);
  ASSERT_EQ(planner.Plan(J(-2), J(2), Deadline::Infinite()).outcome,
            PathOutcome::kNoPathWithinDeadline);
  ASSERT_EQ(planner.remembered_failures(), 1);
  const PathResult r = planner.Plan(J(-4, 0, 3), J(2), Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_FALSE(r.repeated_failure);  // RRT-Connect ran
  EXPECT_EQ(planner.remembered_failures(), 2);
}

TEST(RememberFailures, OffByDefaultAndNotForTimeLimitedQueries) {
  JointBallChecker checker;
  checker.AddShell(J(2), 0.5, 0.8);
  PathOptions options = RememberingOptions();
  options.remember_failures = false;
  PathPlanner off(checker, JointLimits(), options);
  const PathResult a = off.Plan(J(-2), J(2), Deadline::Infinite());
  const PathResult b = off.Plan(J(-2), J(2), Deadline::Infinite());
  EXPECT_EQ(off.remembered_failures(), 0);
  EXPECT_FALSE(b.repeated_failure);
  EXPECT_EQ(a.checks, b.checks);  // the same work again
  EXPECT_FALSE(PathOptions().remember_failures);
  // Stopped by the time limit (no bound on states): no evidence, nothing remembered.
  PathOptions timed;
  timed.time_limit_s = 0.05;
  timed.remember_failures = true;
  PathPlanner by_time(checker, JointLimits(), timed);
  EXPECT_EQ(by_time.Plan(J(-2), J(2), Deadline::Infinite()).outcome,
            PathOutcome::kNoPathWithinDeadline);
  EXPECT_EQ(by_time.remembered_failures(), 0);
}

PathOptions WalledInOptions() {
  PathOptions options;
  options.time_limit_s = 60.0;  // bounds in work, not time, stop these queries
  options.max_tree_states = 400;
  options.walled_in_after_states = 60;
  options.walled_in_goal_fraction = 0.1;
  return options;
}

TEST(WalledIn, AGoalInAPocketFailsEarlyWithItsOutcome) {
  JointBallChecker checker;
  checker.AddShell(J(2), 0.5, 0.8);  // the goal's tree cannot leave its pocket
  const PathResult walled =
      PathPlanner(checker, JointLimits(), WalledInOptions()).Plan(J(-2), J(2), Deadline::Infinite());
  EXPECT_EQ(walled.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_TRUE(walled.walled_in);
  EXPECT_TRUE(walled.waypoints.empty());
  EXPECT_NE(walled.message.find("goals walled in"), std::string::npos) << walled.message;
  const int total = walled.start_tree_states + walled.goal_tree_states;
  EXPECT_GE(total, 60);
  EXPECT_LT(total, 400);
  EXPECT_LE(walled.goal_tree_states * 10, total);
  // Without the rule the same query runs to the bound on states: more work, same outcome.
  PathOptions off = WalledInOptions();
  off.walled_in_after_states = 0;
  const PathResult full =
      PathPlanner(checker, JointLimits(), off).Plan(J(-2), J(2), Deadline::Infinite());
  EXPECT_EQ(full.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_FALSE(full.walled_in);
  EXPECT_GE(full.start_tree_states + full.goal_tree_states, 400);
  EXPECT_GT(full.checks, 2 * walled.checks);
  EXPECT_EQ(PathOptions().walled_in_after_states, 0);  // off by default
}

TEST(WalledIn, AStartInAPocketIsNotAWalledInGoal) {
  JointBallChecker checker;
  checker.AddShell(J(-2), 0.5, 0.8);  // the start's tree is stuck; the goals' grows
  const PathResult r =
      PathPlanner(checker, JointLimits(), WalledInOptions()).Plan(J(-2), J(2), Deadline::Infinite());
  EXPECT_EQ(r.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_FALSE(r.walled_in) << r.message;
  EXPECT_GE(r.start_tree_states + r.goal_tree_states, 400);
  EXPECT_GT(r.goal_tree_states, r.start_tree_states);
}

TEST(WalledIn, GoalsThatCanBeReachedAreStillPlanned) {
  JointBallChecker checker;
  checker.AddBall(J(-0.5, 2), 0.7);
  checker.AddShell(J(2), 0.5, 0.8);
  const JointLimits limits;
  PathPlanner planner(checker, limits, WalledInOptions());
  // Behind a ball (RRT-Connect needed), with a walled-in goal among the goals: the free goal's
  // tree grows, so the query is not walled in, and reaches it.
  const Joints start = J(-2, 2.1), goal = J(1, 2, 0.1);
  ASSERT_FALSE(checker.IsMotionFree(start, goal, 0.01));
  const std::vector<Joints> goals = {J(2), goal};
  const PathResult r = planner.PlanToAny(start, goals, Deadline::Infinite());
  ASSERT_EQ(r.outcome, PathOutcome::kSolved) << r.message;
  EXPECT_FALSE(r.walled_in);
  EXPECT_EQ(r.goal_index, 1);
  ExpectValidPath(checker, limits, r, start, goal);
}

TEST(WalledIn, AWalledInQueryIsRemembered) {
  JointBallChecker checker;
  checker.AddShell(J(2), 0.5, 0.8);
  PathOptions options = WalledInOptions();
  options.remember_failures = true;
  PathPlanner planner(checker, JointLimits(), options);
  const PathResult first = planner.Plan(J(-2), J(2), Deadline::Infinite());
  ASSERT_TRUE(first.walled_in) << first.message;
  EXPECT_EQ(planner.remembered_failures(), 1);
  const PathResult again = planner.Plan(J(-2.2, 0.3), J(2, 0.1), Deadline::Infinite());
  EXPECT_EQ(again.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_TRUE(again.repeated_failure) << again.message;
  EXPECT_FALSE(again.walled_in);
}

TEST(WalledIn, BadOptionsAreRejected) {
  for (const auto& [field, set] :
       std::vector<std::pair<std::string, std::function<void(PathOptions&)>>>{
           {"walled_in_after_states", [](PathOptions& o) { o.walled_in_after_states = -1; }},
           {"walled_in_goal_fraction", [](PathOptions& o) { o.walled_in_goal_fraction = -0.1; }},
           {"walled_in_goal_fraction", [](PathOptions& o) { o.walled_in_goal_fraction = 1.0; }},
           {"walled_in_goal_fraction",
            [](PathOptions& o) { o.walled_in_goal_fraction = std::nan(""); }}}) {
    PathOptions options;
    set(options);
    const absl::Status status = options.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_NE(status.message().find(field), std::string::npos) << status.message();
  }
}

// Elbow flips (PathOptions::flip_max_tree_states): q3, the elbow, changes sign between the start
// and every goal.
PathOptions FlipOptions() {
  PathOptions options;
  options.time_limit_s = 60.0;  // bounds in work, not time, stop these queries
  options.max_tree_states = 400;
  options.flip_max_tree_states = 100;
  return options;
}

TEST(FlipBound, AnElbowFlipToAPocketGivesUpAtItsOwnBound) {
  JointBallChecker checker;
  checker.AddShell(J(2, 0, 0.3), 0.5, 0.8);  // holds goals on both sides of q3 = 0
  const Joints start = J(-2, 0, -1), across = J(2, 0, 0.6), same_side = J(2, 0, -0.1);
  PathPlanner planner(checker, JointLimits(), FlipOptions());
  const PathResult flip = planner.Plan(start, across, Deadline::Infinite());
  EXPECT_EQ(flip.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_TRUE(flip.flip_bound) << flip.message;
  EXPECT_TRUE(flip.waypoints.empty());
  const int total = flip.start_tree_states + flip.goal_tree_states;
  EXPECT_GE(total, 100);
  EXPECT_LT(total, 400);
  // The only way (home): the usual bound, more work, the same outcome.
  const std::vector<Joints> goal = {across};
  const PathResult only = planner.PlanToAny(start, goal, Deadline::Infinite(), /*only_way=*/true);
  EXPECT_EQ(only.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_FALSE(only.flip_bound);
  EXPECT_GE(only.start_tree_states + only.goal_tree_states, 400);
  EXPECT_GT(only.checks, 2 * flip.checks);
  // A goal on the start's side among the goals: not a flip, the usual bound.
  const std::vector<Joints> both = {across, same_side};
  const PathResult mixed = planner.PlanToAny(start, both, Deadline::Infinite());
  EXPECT_EQ(mixed.outcome, PathOutcome::kNoPathWithinDeadline);
  EXPECT_FALSE(mixed.flip_bound);
  EXPECT_GE(mixed.start_tree_states + mixed.goal_tree_states, 400);
  EXPECT_EQ(PathOptions().flip_max_tree_states, 0);  // off by default
}

TEST(FlipBound, ARememberedFlipFailureRefusesOnlyQueriesWithNoLargerBound) {
  JointBallChecker checker;
  checker.AddShell(J(2, 0, 0.3), 0.5, 0.8);
  const Joints start = J(-2, 0, -1), across = J(2, 0, 0.6);
  PathOptions options = FlipOptions();
  options.remember_failures = true;
  PathPlanner planner(checker, JointLimits(), options);
  const PathResult flip = planner.Plan(start, across, Deadline::Infinite());
  ASSERT_TRUE(flip.flip_bound) << flip.message;
  EXPECT_EQ(planner.remembered_failures(), 1);
  // The same flip again: refused.
  const PathResult again = planner.Plan(start, across, Deadline::Infinite());
  EXPECT_TRUE(again.repeated_failure) << again.message;
  // The way home may grow larger trees: searched to the usual bound, not refused.
  const std::vector<Joints> goal = {across};
  const PathResult home = planner.PlanToAny(start, goal, Deadline::Infinite(), /*only_way=*/true);
  EXPECT_FALSE(home.repeated_failure) << home.message;
  EXPECT_GE(home.start_tree_states + home.goal_tree_states, 400);
  // The other way round: a failure at the usual bound refuses a later flip (allowed fewer).
  PathPlanner fresh(checker, JointLimits(), options);
  const PathResult usual = fresh.PlanToAny(start, goal, Deadline::Infinite(), /*only_way=*/true);
  ASSERT_FALSE(usual.flip_bound) << usual.message;
  EXPECT_EQ(fresh.remembered_failures(), 1);
  const PathResult later_flip = fresh.Plan(start, across, Deadline::Infinite());
  EXPECT_TRUE(later_flip.repeated_failure) << later_flip.message;
}

TEST(FlipBound, AnElbowFlipThatCanBeMadeIsStillPlanned) {
  JointBallChecker checker;
  checker.AddBall(J(0), 1.0);
  const JointLimits limits;
  const Joints start = J(-2, 0, -0.5), goal = J(2, 0, 0.5);
  ASSERT_FALSE(checker.IsMotionFree(start, goal, 0.01));  // RRT-Connect is needed
  PathPlanner planner(checker, limits, FlipOptions());
  const PathResult r = planner.Plan(start, goal, Deadline::Infinite());
  ExpectValidPath(checker, limits, r, start, goal);
  EXPECT_FALSE(r.flip_bound);
  EXPECT_LT(r.start_tree_states + r.goal_tree_states, 100);
}

TEST(FlipBound, NegativeBoundIsRejected) {
  PathOptions options;
  options.flip_max_tree_states = -1;
  const absl::Status status = options.Validate();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("flip_max_tree_states"), std::string::npos) << status.message();
}

}  // namespace
}  // namespace vb::plan
