// SPDX-License-Identifier: Apache-2.0
// Shortening a joint-space path found by a sampling planner (PathPlanner shortcuts every
// RRT-Connect path with it): random shortcuts that lower the path's execution time (MoveTimeS),
// as OMPL's PathSimplifier::shortcutPath draws them, and greedy removal of waypoints. Every
// segment it makes is checked with CollisionChecker::IsMotionFree. Thread-compatible (the checker
// is not thread-safe).
#pragma once

#include <cstdint>
#include <vector>

#include "core/deadline.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

// Whether two configurations are the same waypoint: every joint within 1e-12 rad. A path never
// keeps two such waypoints in a row (ShortcutPath, PathPlanner).
inline bool SameWaypoint(const Joints& a, const Joints& b) {
  return (a - b).cwiseAbs().maxCoeff() < 1e-12;
}

// Shortens `waypoints` in place (first and last kept): waypoints that can be skipped are removed
// greedily (each new segment checked); then `rounds` times, two random points on the path
// (anywhere along its segments, drawn from `seed`) are joined by a straight segment when
// IsMotionFree(max_step_m) and the path's total MoveTimeS drops; then the greedy removal again.
// Stops early at the deadline. Returns the number of shortcuts taken. Input segments are not
// checked: those it keeps are returned bit-exact (same consecutive waypoints), and every segment
// it makes (the remnants of input segments cut at a new point included) has passed
// IsMotionFree(max_step_m).
int ShortcutPath(CollisionChecker& checker, const JointLimits& limits, double max_step_m,
                 int rounds, uint64_t seed, const Deadline& deadline,
                 std::vector<Joints>& waypoints);

}  // namespace vb::plan
