// SPDX-License-Identifier: Apache-2.0
// PathPlanner's queries: validation, the straight segments, the bounds on RRT-Connect's trees
// (rrt_connect.h runs it through OMPL), the remembered failed queries, the check of a path found
// with coarse edges, and shortcutting (path_shortcut.h).
#include "workers/plan/path_planner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "workers/plan/path_shortcut.h"
#include "workers/plan/rrt_connect.h"

namespace vb::plan {

namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Whether a -> b is a segment of `path` (consecutive waypoints, bit-exact): shortcutting keeps
// such segments as they are and checks every segment it makes.
bool IsTreeSegment(const std::vector<Joints>& path, const Joints& a, const Joints& b) {
  for (size_t k = 0; k + 1 < path.size(); ++k) {
    if (path[k] == a && path[k + 1] == b) return true;
  }
  return false;
}

// Failed queries a planner remembers (PathOptions::remember_failures); later ones are not kept.
constexpr size_t kMaxRememberedFailures = 32;
// A configuration joins a remembered tree through one of its kJoinNearest nearest states within
// kJoinRange * range_rad (PathOptions::remember_failures).
constexpr int kJoinNearest = 8;
constexpr double kJoinRange = 3.0;

}  // namespace

absl::Status PathOptions::Validate() const {
  if (!(max_step_m > 0.0) || !std::isfinite(max_step_m)) {
    return absl::InvalidArgumentError("path options: max_step_m: must be finite and > 0");
  }
  if (!(tree_max_step_m >= 0.0) || !std::isfinite(tree_max_step_m)) {
    return absl::InvalidArgumentError("path options: tree_max_step_m: must be finite and >= 0");
  }
  if (!(range_rad >= 0.0) || !std::isfinite(range_rad)) {
    return absl::InvalidArgumentError("path options: range_rad: must be finite and >= 0");
  }
  if (!(time_limit_s > 0.0)) {
    return absl::InvalidArgumentError("path options: time_limit_s: must be > 0");
  }
  if (max_tree_states < 0) {
    return absl::InvalidArgumentError("path options: max_tree_states: must be >= 0");
  }
  if (flip_max_tree_states < 0) {
    return absl::InvalidArgumentError("path options: flip_max_tree_states: must be >= 0");
  }
  if (walled_in_after_states < 0) {
    return absl::InvalidArgumentError("path options: walled_in_after_states: must be >= 0");
  }
  if (!(walled_in_goal_fraction >= 0.0) || !(walled_in_goal_fraction < 1.0)) {
    return absl::InvalidArgumentError("path options: walled_in_goal_fraction: must be in [0, 1)");
  }
  if (shortcut_rounds < 0) {
    return absl::InvalidArgumentError("path options: shortcut_rounds: must be >= 0");
  }
  return absl::OkStatus();
}

std::string_view PathOutcomeName(PathOutcome outcome) {
  switch (outcome) {
    case PathOutcome::kSolved: return "solved";
    case PathOutcome::kStartInCollision: return "start_in_collision";
    case PathOutcome::kGoalInCollision: return "goal_in_collision";
    case PathOutcome::kOutsideLimits: return "outside_limits";
    case PathOutcome::kNoPathWithinDeadline: return "no_path_within_deadline";
    case PathOutcome::kInvalidInput: return "invalid_input";
  }
  return "unknown";
}

PathPlanner::PathPlanner(CollisionChecker& checker, const JointLimits& limits,
                         const PathOptions& options)
    : checker_(checker), limits_(limits), options_(options) {
  setup_status_ = limits_.Validate();
  if (setup_status_.ok()) setup_status_ = options_.Validate();
  if (!setup_status_.ok()) return;
  absl::StatusOr<std::unique_ptr<RrtConnect>> rrt =
      RrtConnect::Create(checker_, limits_, options_.range_rad);
  if (!rrt.ok()) {
    setup_status_ = rrt.status();
    return;
  }
  rrt_ = *std::move(rrt);
}

PathPlanner::~PathPlanner() = default;

PathResult PathPlanner::Plan(const Joints& start, const Joints& goal, const Deadline& deadline) {
  return PlanToAny(start, std::span<const Joints>(&goal, 1), deadline);
}

PathResult PathPlanner::PlanToAny(const Joints& start, std::span<const Joints> goals,
                                  const Deadline& deadline, bool only_way) {
  const Clock::time_point t0 = Clock::now();
  const int64_t checks0 = checker_.checks();
  PathResult result;
  auto finish = [&](PathOutcome outcome, std::string message) {
    result.outcome = outcome;
    result.message = std::move(message);
    if (outcome != PathOutcome::kSolved) {
      result.waypoints.clear();
      result.goal_index = -1;
    }
    result.checks = checker_.checks() - checks0;
    result.planning_s = SecondsSince(t0);
    return result;
  };

  if (!setup_status_.ok()) return finish(PathOutcome::kInvalidInput, std::string(setup_status_.message()));
  if (goals.empty()) return finish(PathOutcome::kInvalidInput, "goals: empty");
  if (!start.allFinite()) return finish(PathOutcome::kInvalidInput, "start: non-finite joint value");
  for (size_t g = 0; g < goals.size(); ++g) {
    if (!goals[g].allFinite()) {
      return finish(PathOutcome::kInvalidInput,
                    goals.size() == 1 ? std::string("goal: non-finite joint value")
                                      : absl::StrCat("goals[", g, "]: non-finite joint value"));
    }
  }
  if (!limits_.Contains(start)) return finish(PathOutcome::kOutsideLimits, "start: outside the joint limits");
  // The goals that can be reached at all; the first goal's reason when none can.
  std::vector<int> usable;
  PathOutcome first_outcome = PathOutcome::kSolved;
  std::string first_message;
  for (size_t g = 0; g < goals.size(); ++g) {
    const std::string name = goals.size() == 1 ? "goal" : absl::StrCat("goals[", g, "]");
    if (!limits_.Contains(goals[g])) {
      if (g == 0) first_outcome = PathOutcome::kOutsideLimits, first_message = name + ": outside the joint limits";
      continue;
    }
    if (g == 0 && !checker_.IsFree(start)) {
      return finish(PathOutcome::kStartInCollision, "start: in collision");
    }
    if (!checker_.IsFree(goals[g])) {
      if (g == 0) first_outcome = PathOutcome::kGoalInCollision, first_message = name + ": in collision";
      continue;
    }
    usable.push_back(static_cast<int>(g));
  }
  if (usable.empty()) return finish(first_outcome, first_message);
  if (usable.front() != 0 && !checker_.IsFree(start)) {
    return finish(PathOutcome::kStartInCollision, "start: in collision");
  }

  for (int g : usable) {
    if (SameWaypoint(start, goals[g]) ||
        (options_.try_direct_first && checker_.IsMotionFree(start, goals[g], options_.max_step_m))) {
      result.waypoints = {start, goals[g]};
      result.direct = true;
      result.goal_index = g;
      return finish(PathOutcome::kSolved, "");
    }
  }
  if (deadline.Expired()) {
    return finish(PathOutcome::kNoPathWithinDeadline, "deadline expired before RRT-Connect");
  }
  // Elbow flips give up sooner (PathOptions::flip_max_tree_states) unless they are the only way.
  bool flip = !only_way && options_.flip_max_tree_states > 0 &&
              (options_.max_tree_states == 0 ||
               options_.flip_max_tree_states < options_.max_tree_states);
  for (int g : usable) flip = flip && (goals[g][2] > 0.0) != (start[2] > 0.0);
  const int bound = flip ? options_.flip_max_tree_states : options_.max_tree_states;
  const size_t max_states = bound > 0 ? static_cast<size_t>(bound) : SIZE_MAX;
  if (options_.remember_failures) {
    if (const int f = RepeatsFailure(start, goals, usable, max_states); f >= 0) {
      result.repeated_failure = true;
      return finish(PathOutcome::kNoPathWithinDeadline,
                    absl::StrCat("like failed query ", f, " of this planner: the start joins its "
                                 "start's tree and every goal its goals' tree (",
                                 failures_[f].start_side.size(), " and ",
                                 failures_[f].goal_side.size(), " states)"));
    }
  }

  const double budget_s = std::min(options_.time_limit_s, deadline.RemainingS());
  const Clock::time_point end =
      budget_s >= 1e9 ? Clock::time_point::max()
                      : Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(budget_s));
  // RRT-Connect checks its edges at tree_max_step_m; the path it returns is then checked at
  // max_step_m, and if that finds a collision the query runs again with the edges checked at
  // max_step_m (same seed, same bounds, within what is left of the time limit).
  std::vector<Joints> usable_goals;
  usable_goals.reserve(usable.size());
  for (int g : usable) usable_goals.push_back(goals[g]);
  // Goals walled in (PathOptions::walled_in_after_states).
  const size_t wall_after = options_.walled_in_after_states > 0
                                ? static_cast<size_t>(options_.walled_in_after_states)
                                : SIZE_MAX;
  const double wall_fraction = options_.walled_in_goal_fraction;
  const double coarse_m = std::max(options_.tree_max_step_m, options_.max_step_m);
  for (const double edge_step_m : {coarse_m, options_.max_step_m}) {
    result.waypoints.clear();
    bool walled_in = false;
    const absl::StatusOr<RrtRun> run = rrt_->Run(
        start, usable_goals, options_.seed, edge_step_m,
        [&end, &deadline, max_states, wall_after, wall_fraction, &walled_in](size_t start_side,
                                                                            size_t goal_side) {
          const size_t total = goal_side + start_side;
          if (total >= wall_after && static_cast<double>(goal_side) <= wall_fraction * total) {
            walled_in = true;
          }
          return walled_in || total >= max_states || Clock::now() >= end || deadline.Cancelled();
        });
    if (!run.ok()) return finish(PathOutcome::kNoPathWithinDeadline, std::string(run.status().message()));
    result.start_tree_states = static_cast<int>(run->start_tree_states);
    result.goal_tree_states = static_cast<int>(run->goal_tree_states);
    const size_t total = run->start_tree_states + run->goal_tree_states;
    if (!run->exact) {
      // Only a query stopped by the bound on states is remembered: one stopped by time says
      // nothing reproducible.
      if (options_.remember_failures && failures_.size() < kMaxRememberedFailures &&
          (walled_in || total >= max_states)) {
        // A walled-in query ends whatever its bound; one stopped by the bound refuses only
        // queries allowed no more states (a flip's failure does not refuse the way home).
        failures_.push_back({rrt_->TreeStates(/*start_side=*/true),
                             rrt_->TreeStates(/*start_side=*/false),
                             walled_in ? SIZE_MAX : max_states});
      }
      result.flip_bound = flip && !walled_in && total >= max_states;
      if (walled_in) {
        result.walled_in = true;
        return finish(PathOutcome::kNoPathWithinDeadline,
                      absl::StrCat("goals walled in: their tree holds ", run->goal_tree_states,
                                   " of the ", total, " states of both (walled_in_goal_fraction ",
                                   wall_fraction, ")"));
      }
      return finish(PathOutcome::kNoPathWithinDeadline,
                    absl::StrCat("RRT-Connect found no exact path within ", budget_s, " s (",
                                 run->status, ")"));
    }
    for (const Joints& q : run->path) {
      if (result.waypoints.empty() || !SameWaypoint(result.waypoints.back(), q)) {
        result.waypoints.push_back(q);
      }
    }
    if (result.waypoints.size() < 2) {
      return finish(PathOutcome::kNoPathWithinDeadline, "RRT-Connect returned a degenerate path");
    }
    // The path ends at a copy of one of the goals: find which (the nearest; copies are exact),
    // and make the ends bit-exact so callers can chain paths.
    double best = std::numeric_limits<double>::infinity();
    for (int g : usable) {
      const double d = (goals[g] - result.waypoints.back()).cwiseAbs().maxCoeff();
      if (d < best) best = d, result.goal_index = g;
    }
    if (best > 1e-9) {
      return finish(PathOutcome::kNoPathWithinDeadline, "RRT-Connect's path ends at no goal");
    }
    result.waypoints.front() = start;
    result.waypoints.back() = goals[result.goal_index];
    // Shortcut first: every segment shortcutting makes is checked at max_step_m, so only the
    // tree's own segments that remain need the check at max_step_m (most are shortcut away).
    const std::vector<Joints> tree_path =
        edge_step_m > options_.max_step_m ? result.waypoints : std::vector<Joints>();
    ShortcutPath(checker_, limits_, options_.max_step_m, options_.shortcut_rounds, options_.seed,
                 deadline, result.waypoints);
    if (edge_step_m <= options_.max_step_m) break;  // every edge was checked at max_step_m
    bool fine = true;
    for (size_t k = 0; fine && k + 1 < result.waypoints.size(); ++k) {
      if (IsTreeSegment(tree_path, result.waypoints[k], result.waypoints[k + 1])) {
        fine = checker_.IsMotionFree(result.waypoints[k], result.waypoints[k + 1],
                                     options_.max_step_m);
      }
    }
    if (fine) break;
    ++result.coarse_rejections;
    if (deadline.Expired() || Clock::now() >= end) {
      return finish(PathOutcome::kNoPathWithinDeadline,
                    "RRT-Connect's path collided at max_step_m and no time was left to replan");
    }
  }
  return finish(PathOutcome::kSolved, "");
}

bool PathPlanner::Joins(const Joints& q, const std::vector<Joints>& tree) {
  // The kJoinNearest nearest states (squared distances); a state equal to q (up to rounding:
  // a goal shifted by whole turns again) joins at once.
  constexpr int kNearest = kJoinNearest;
  std::pair<double, int> best[kNearest];
  for (auto& b : best) b = {std::numeric_limits<double>::infinity(), -1};
  for (size_t i = 0; i < tree.size(); ++i) {
    const double d = (tree[i] - q).squaredNorm();
    if (d < 1e-18) return true;
    if (d < best[kNearest - 1].first) {
      best[kNearest - 1] = {d, static_cast<int>(i)};
      for (int k = kNearest - 1; k > 0 && best[k].first < best[k - 1].first; --k)
        std::swap(best[k], best[k - 1]);
    }
  }
  const double range = options_.range_rad > 0.0 ? options_.range_rad
                                                : std::numeric_limits<double>::infinity();
  const double step_m = std::max(options_.tree_max_step_m, options_.max_step_m);
  for (const auto& [d, i] : best) {
    if (i < 0 || std::sqrt(d) > kJoinRange * range) continue;
    if (checker_.IsMotionFree(q, tree[i], step_m)) return true;
  }
  return false;
}

int PathPlanner::RepeatsFailure(const Joints& start, std::span<const Joints> goals,
                                const std::vector<int>& usable, size_t max_states) {
  for (size_t f = 0; f < failures_.size(); ++f) {
    const FailedQuery& failed = failures_[f];
    if (failed.max_states < max_states) continue;  // this query may grow larger trees
    // Goals first: they repeat exactly when a cut is tried again from another start.
    bool all = true;
    for (int g : usable) {
      if (!Joins(goals[g], failed.goal_side)) {
        all = false;
        break;
      }
    }
    if (all && Joins(start, failed.start_side)) return static_cast<int>(f);
  }
  return -1;
}

PathResult PlanPath(CollisionChecker& checker, const JointLimits& limits, const Joints& start,
                    const Joints& goal, const PathOptions& options, const Deadline& deadline) {
  const Clock::time_point t0 = Clock::now();
  PathPlanner planner(checker, limits, options);
  PathResult result = planner.Plan(start, goal, deadline);
  result.planning_s = SecondsSince(t0);
  return result;
}

}  // namespace vb::plan
