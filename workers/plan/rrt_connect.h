// SPDX-License-Identifier: Apache-2.0
// Internal to PathPlanner (path_planner.cc): one RRT-Connect run (Kuffner & LaValle, ICRA 2000;
// OMPL's implementation) in the arm's joint space, with our CollisionChecker as OMPL's state
// validity checker and motion validator. OMPL, its headers and its exceptions stay inside
// rrt_connect.cc; nothing here throws.
//
// The run is rooted at every goal at once and at the start: OMPL's start states are our goals and
// its goal state is our start (OMPL roots its start tree at every start state before the first
// iteration but adds goal states one at a time, so a walled-in first goal would hide the others);
// the path is handed back from our start to a goal. Its random samples come from our own sampler,
// seeded from `seed` on every run (never from OMPL's process-wide seed), so a run that is not
// stopped by time depends only on the checker, limits, range, seed, edge resolution, start and
// goals. Not thread-safe (nor is the checker); the checker must outlive it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "absl/functional/function_ref.h"
#include "absl/status/statusor.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

struct RrtRun {
  bool exact = false;  // an exact path was found
  std::string status;  // OMPL's planner status, e.g. "Exact solution" or "Timeout"
  // On `exact`: OMPL's path from the start to a copy of one of the goals, as it gave it (it may
  // repeat a state; its ends are copies of the start and a goal, not bit-exact).
  std::vector<Joints> path;
  // States in the tree rooted at the start and in the one rooted at the goals when it stopped.
  size_t start_tree_states = 0, goal_tree_states = 0;
};

class RrtConnect {
 public:
  // OMPL's state space (bounded by `limits`), space information and planner, set up once.
  // `range_rad` is RRT-Connect's step (0: OMPL's default). INTERNAL when OMPL's setup throws.
  static absl::StatusOr<std::unique_ptr<RrtConnect>> Create(CollisionChecker& checker,
                                                            const JointLimits& limits,
                                                            double range_rad);
  ~RrtConnect();
  RrtConnect(const RrtConnect&) = delete;
  RrtConnect& operator=(const RrtConnect&) = delete;

  // Clears the trees and runs RRT-Connect from `start` to any of `goals` (non-empty, within the
  // limits, free), checking tree edges with IsMotionFree(edge_step_m), until a path is found or
  // `stop(start_tree_states, goal_tree_states)` returns true (asked at every iteration).
  // INTERNAL with "OMPL: " and the message of an exception OMPL threw.
  absl::StatusOr<RrtRun> Run(const Joints& start, std::span<const Joints> goals, uint64_t seed,
                             double edge_step_m,
                             absl::FunctionRef<bool(size_t start_tree, size_t goal_tree)> stop);

  // The states of the last run's tree rooted at the start (start_side) or at the goals.
  std::vector<Joints> TreeStates(bool start_side) const;

 private:
  struct Ompl;  // OMPL objects, defined in the .cc
  explicit RrtConnect(std::unique_ptr<Ompl> ompl);
  std::unique_ptr<Ompl> ompl_;
};

}  // namespace vb::plan
