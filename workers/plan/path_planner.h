// SPDX-License-Identifier: Apache-2.0
// Collision-free joint-space paths between two configurations of the arm: the straight segment
// when it is free (as VAMP does, Thomason et al. ICRA 2024), else RRT-Connect (Kuffner & LaValle,
// ICRA 2000; OMPL's implementation) with our CollisionChecker as OMPL's StateValidityChecker and
// MotionValidator (rrt_connect.h), then shortcutting (path_shortcut.h). Every segment of a
// returned path has been checked with
// CollisionChecker::IsMotionFree at the requested resolution; the arm is meant to follow those
// straight joint-space segments exactly (see time_parameterization.h).
//
// Determinism: a result depends only on the checker, limits, start, goal and options (the seed
// included) — not on earlier calls or other planners in the process — as long as the planning
// time limit is not reached, and, with PathOptions::remember_failures, on the planner's earlier
// failed queries (which it may refuse to search again). OMPL's global seed (ompl::RNG::setSeed) is not used: the random
// samples RRT-Connect draws come from our own state sampler seeded from options.seed on every
// call, and shortcutting uses its own generator. A plan cut short by the time limit or deadline
// depends on timing, and so cannot be reproduced.
//
// OMPL and its exceptions stay inside rrt_connect.cc; nothing here throws. OMPL's console log
// is silenced (process-wide, at the first valid PathPlanner) down to errors.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "core/deadline.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

class RrtConnect;  // rrt_connect.h

struct PathOptions {
  double max_step_m = 0.01;       // motion-check resolution: max travel of any arm point, m
  // RRT-Connect's edges are checked at this resolution (m; <= max_step_m or 0: max_step_m); the
  // path it finds is shortcut (every new segment checked at max_step_m), then its segments that
  // shortcutting kept are checked at max_step_m, and the query is planned again with edges at
  // max_step_m if that check fails (PathResult::coarse_rejections). Most tree edges never reach
  // the path, and most of the path's are shortcut away, so a coarser resolution for them saves
  // checks; the returned segments are always checked at max_step_m.
  double tree_max_step_m = 0.0;
  double range_rad = 1.0;         // RRT-Connect step (joint-space length); 0 = OMPL's default
  double time_limit_s = 1.0;      // planning time per call (also bounded by the deadline)
  // RRT-Connect gives up once its trees hold this many states together (0 = no bound): a bound
  // in work, not time: a query stopped by it costs the same and ends the same whatever the
  // machine's load (one stopped by time_limit_s does not).
  int max_tree_states = 0;
  int shortcut_rounds = 60;       // random shortcut attempts after RRT-Connect (0 = none)
  uint64_t seed = 1;              // seeds RRT-Connect's samples and the shortcuts
  bool try_direct_first = true;   // check the straight segment before running RRT-Connect
  // Remember the two trees of every query that RRT-Connect gave up on at max_tree_states (not
  // one stopped by time or the deadline), and fail a later query of the same planner at once,
  // before RRT-Connect, when its start joins such a query's start-side tree and every one of its
  // goals the goal-side tree (PathResult::repeated_failure): it would search the same two
  // regions again. A configuration joins a tree when it is one of its states or the straight
  // segment to one of the tree's eight nearest states (within 3 range_rad) is free at the tree-edge
  // resolution. A query stopped by its bound on states refuses only later queries allowed no
  // more states (an elbow flip's failure at flip_max_tree_states does not refuse the way home).
  // Makes results depend on the planner's earlier queries; meant for the queries of one scene
  // (ForgetFailures() when the checker's scene changes).
  bool remember_failures = false;
  // Goals walled in: RRT-Connect gives up once its trees hold walled_in_after_states states or
  // more together (0 = never) while the tree rooted at the goals holds at most
  // walled_in_goal_fraction of them (PathResult::walled_in): its extensions keep colliding, and
  // the start's tree grows alone. A bound in work, like max_tree_states, so it ends the same
  // whatever the load; such a query is remembered as failed (remember_failures). At or above
  // max_tree_states (when that bound is set) it never fires: the bound ends the query first.
  int walled_in_after_states = 0;
  double walled_in_goal_fraction = 0.1;
  // Elbow flips: a query whose start and every usable goal lie on opposite sides of the elbow's
  // straight configuration (q3 = 0) gives up at this many states instead of max_tree_states
  // (0 = no other bound; used only below max_tree_states), unless the caller says the query is
  // its only way to its goals (PlanToAny's only_way: the way home). PathResult::flip_bound.
  int flip_max_tree_states = 0;

  // INVALID_ARGUMENT naming the field: max_step_m <= 0 or non-finite, tree_max_step_m < 0 or
  // non-finite, range_rad < 0, time_limit_s <= 0 or NaN, max_tree_states < 0,
  // walled_in_after_states < 0, walled_in_goal_fraction outside [0, 1), shortcut_rounds < 0,
  // flip_max_tree_states < 0.
  absl::Status Validate() const;
};

enum class PathOutcome {
  kSolved,
  kStartInCollision,
  kGoalInCollision,
  kOutsideLimits,         // start or goal outside the joint limits
  kNoPathWithinDeadline,  // RRT-Connect found no exact path in time (approximate ones count here)
  kInvalidInput,          // non-finite joints, invalid limits or options
};
// "solved", "start_in_collision", "goal_in_collision", "outside_limits",
// "no_path_within_deadline", "invalid_input".
std::string_view PathOutcomeName(PathOutcome outcome);

struct PathResult {
  PathOutcome outcome = PathOutcome::kInvalidInput;
  std::string message;              // why, on anything but kSolved
  std::vector<Joints> waypoints;    // start .. goal on kSolved (>= 2; start == goal gives 2)
  int64_t checks = 0;               // configuration checks spent (checker.checks() delta)
  double planning_s = 0.0;          // wall time of the call
  bool direct = false;              // the straight segment start -> goal was free
  int goal_index = -1;              // on kSolved, which goal the path ends at (PlanToAny)
  // RRT-Connect paths found with coarse edge checks (tree_max_step_m) whose segments left after
  // shortcutting collided at max_step_m, so that the query was planned again (0 or 1).
  int coarse_rejections = 0;
  // kNoPathWithinDeadline without running RRT-Connect: the start and goals join the trees of an
  // earlier failed query (PathOptions::remember_failures).
  bool repeated_failure = false;
  // kNoPathWithinDeadline at PathOptions::flip_max_tree_states (an elbow flip given up early).
  bool flip_bound = false;
  // States in RRT-Connect's two trees when it stopped (0 when it did not run): the tree rooted at
  // the start and the one rooted at the goals (of its last run, after a coarse rejection).
  int start_tree_states = 0, goal_tree_states = 0;
  // kNoPathWithinDeadline because the goals' tree stopped growing (PathOptions::walled_in_*).
  // Distinct from a query stopped at max_tree_states or the time limit.
  bool walled_in = false;
};

// A planning context bound to one checker and one set of limits and options: holds OMPL's state
// space, space information, RRT-Connect and problem definition so that repeated queries pay no
// setup. Not thread-safe (nor is the checker); use one per thread. The checker must outlive it.
class PathPlanner {
 public:
  // Invalid limits or options are reported by every Plan() call as kInvalidInput.
  PathPlanner(CollisionChecker& checker, const JointLimits& limits, const PathOptions& options);
  ~PathPlanner();
  PathPlanner(const PathPlanner&) = delete;
  PathPlanner& operator=(const PathPlanner&) = delete;

  // A path from start to goal. Checks, in this order: finite joints (kInvalidInput), limits
  // (kOutsideLimits), start then goal free (kStartInCollision, kGoalInCollision); then the
  // straight segment, then RRT-Connect within min(options.time_limit_s, deadline), then
  // shortcuts (only while the deadline allows; a shortcut is taken when it shortens the
  // execution time of the path, MoveTimeS summed over segments). Never throws, never runs past
  // the bound by more than one collision check batch.
  PathResult Plan(const Joints& start, const Joints& goal, const Deadline& deadline);

  // A path from start to any one of `goals` (e.g. a cut's alternative cut motions), in one query:
  // goals outside the limits or in collision are skipped; the straight segments to the others
  // are tried in the given order (the first free one wins); then ONE RRT-Connect run, within the
  // same time limit as Plan(), grows a tree from every remaining goal at once (the goals are
  // OMPL's start states and `start` its goal, so all of them are roots from the first iteration;
  // the path is reversed). So a set of goals that cannot be reached costs one time limit, not one
  // per goal. result.goal_index names the goal reached. Empty `goals` or a non-finite one:
  // kInvalidInput; when every goal is skipped, the first goal's outcome (kOutsideLimits or
  // kGoalInCollision). Plan(start, goal) is PlanToAny(start, {goal}). `only_way`: the caller has
  // no other start for these goals (the way home), so PathOptions::flip_max_tree_states does not
  // apply.
  PathResult PlanToAny(const Joints& start, std::span<const Joints> goals,
                       const Deadline& deadline, bool only_way = false);

  const PathOptions& options() const { return options_; }

  // Drops the remembered failed queries (remember_failures); needed when the checker's scene
  // changes, since they were grown in the old one.
  void ForgetFailures() { failures_.clear(); }
  // How many failed queries are remembered.
  int remembered_failures() const { return static_cast<int>(failures_.size()); }

 private:
  // The trees of a query RRT-Connect gave up on: rooted at its start and at its goals, and the
  // states it was allowed (SIZE_MAX when walled in: that ends a query whatever its bound).
  struct FailedQuery {
    std::vector<Joints> start_side, goal_side;
    size_t max_states = SIZE_MAX;
  };
  // Whether q joins `tree` (see PathOptions::remember_failures).
  bool Joins(const Joints& q, const std::vector<Joints>& tree);
  // The index of a remembered failed query, allowed at least `max_states` states, whose trees
  // the start and every usable goal join, or -1.
  int RepeatsFailure(const Joints& start, std::span<const Joints> goals,
                     const std::vector<int>& usable, size_t max_states);
  CollisionChecker& checker_;
  JointLimits limits_;
  PathOptions options_;
  absl::Status setup_status_;
  std::unique_ptr<RrtConnect> rrt_;  // null when setup_status_ is not OK
  std::vector<FailedQuery> failures_;
};

// One-shot form: builds a PathPlanner and plans once (OMPL setup included in planning_s).
PathResult PlanPath(CollisionChecker& checker, const JointLimits& limits, const Joints& start,
                    const Joints& goal, const PathOptions& options, const Deadline& deadline);

}  // namespace vb::plan
