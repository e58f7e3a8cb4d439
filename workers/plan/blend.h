// SPDX-License-Identifier: Apache-2.0
// Transit timing that does not stop at interior waypoints: linear segments with parabolic blends
// at the via points (Craig, "Introduction to Robotics", section 7.3, linear function with
// parabolic blends through via points), synchronised so that all joints blend over the same
// interval. The path starts and ends at rest exactly at its first and last waypoints; between
// blends the arm moves at constant joint velocity on the straight segments, so only the blends
// leave the collision-checked path. Each blend is a parabola tangent to both segments (a quadratic
// Bezier curve with the via point as control point), so it stays in the triangle of its three
// waypoints and within joint limits that contain them.
//
// Timing: each segment k has a linear duration T_k and joint velocity v_k = (w_{k+1} - w_k) / T_k;
// at via k the blend lasts tb_k = max_j |v_k,j - v_k-1,j| / amax_j (v_-1 = v_n = 0), so every
// joint stays within its acceleration limit; T_k >= max_j |w_k+1,j - w_k,j| / vmax_j bounds the
// velocity; blends may not overlap: (tb_k + tb_k+1) / 2 <= T_k. The durations start at the
// velocity bound and grow where a constraint is violated (locally, then by one uniform scaling
// that satisfies every constraint at once: v, tb scale as 1/c, T as c). A path of one segment
// gives exactly the rest-to-rest trapezoid of MoveTimeS.
//
// Collisions: with a checker, the chords between successive output samples that overlap a blend
// are checked with IsMotionFree: they are what an executor interpolating the samples follows (and
// what trajectory_check.h re-checks); the parabola stays within amax sample_dt_s^2 / 8 of them
// (1.6 mrad at 5 rad/s^2 and 0.05 s; checking it too in 0.01 s chords quadrupled the timing
// stage's cost and changed nothing on seeds 1110-1119); a colliding blend is made smaller (its
// deviation from the via point bounded, which slows the neighbouring segments) by bisection
// between the largest size found free and the smallest found colliding, starting with half its
// size, for max_shrinks steps; if no smaller size was free the arm stops at that via point (the
// already-checked path). A chord checked in an earlier round (the same two samples bit for bit: a
// run whose stops and blend bounds did not change is laid out again identically) is not checked
// again. A run whose blended timing would be slower than stopping at each of its
// waypoints is stopped at each of them. Thread-safe (pure functions; the checker is used by
// the calling thread only).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "workers/plan/collision_checker.h"
#include "workers/plan/time_parameterization.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

struct BlendOptions {
  double max_step_m = 0.005;  // IsMotionFree resolution on the chords of the blends
  int max_shrinks = 5;        // bisection steps on a colliding blend's size (the first halves it)
  // INVALID_ARGUMENT naming the field.
  absl::Status Validate() const;
};

struct BlendedPath {
  std::vector<TimedJoints> samples;  // start and goal exactly, every stop exactly, t increasing
  double duration_s = 0.0;
  int vias = 0;                      // interior waypoints (after merging repeated ones)
  int stops = 0;                     // interior waypoints where the arm stops
  int shrinks = 0;                   // bisection steps down after a collision
  int64_t checks = 0;                // checker->checks() spent on blends
  // The chords samples[i] -> samples[i + 1] that overlap an interior blend, by increasing i:
  // every other chord lies on a straight segment between two waypoints (the arm starts and ends
  // at rest along its segment, and stops exactly at a stop), so only these leave the path.
  std::vector<int> blend_chords;
};

// Duration of the blended path with every blend at full size (no collision checks): what
// TimeParameterizeBlended returns when no blend collides. <= PathTimeS(waypoints); equal for
// fewer than three distinct waypoints. Limits are assumed valid.
double BlendedPathTimeS(std::span<const Joints> waypoints, const JointLimits& limits);

// Samples every `sample_dt_s` from start_time_s, plus the goal (and every stop) at its exact
// time. `checker` may be null (no checks: every blend kept). Errors as TimeParameterize
// (INVALID_ARGUMENT naming the field), and options.Validate().
absl::StatusOr<BlendedPath> TimeParameterizeBlended(std::span<const Joints> waypoints,
                                                    const JointLimits& limits,
                                                    CollisionChecker* checker,
                                                    const BlendOptions& options,
                                                    double start_time_s, double sample_dt_s);

}  // namespace vb::plan
