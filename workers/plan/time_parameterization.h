// SPDX-License-Identifier: Apache-2.0
// Timing of piecewise-linear joint paths. Rest to rest: the arm stops at every waypoint and moves
// along each straight joint-space segment with one synchronised trapezoidal (or, for short moves,
// triangular) velocity profile, so that it follows the collision-checked segments exactly. All
// joints share the path parameter s(t) in [0, 1], q(t) = a + s(t) (b - a); s accelerates at
// A = min_i amax_i / |d_i|, cruises at V = min_i vmax_i / |d_i| and decelerates at A, so every joint
// stays within its velocity and acceleration limits and the slowest joint saturates. This is the
// fastest rest-to-rest motion that stays on the segment. (URScript movej moves the same way.)
// Dense strokes: one profile along the arc length (TimeParameterizeAlongPath). Transits that do
// not stop at their waypoints: blend.h.
// Thread-safe (pure functions).
#pragma once

#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "workers/plan/ur5_kinematics.h"

namespace vb::plan {

struct TimedJoints {
  double t = 0.0;  // s
  Joints q;        // rad
};

// Duration of the rest-to-rest move a -> b on the straight segment: 0 when a == b, otherwise
// 2 sqrt(1/A) (triangular, when 1 < V^2/A) or 1/V + V/A (trapezoidal). Limits are assumed valid
// (JointLimits::Validate); joint position limits are not consulted. This is also the cost of
// going from a to b used to order the cuts.
double MoveTimeS(const Joints& a, const Joints& b, const JointLimits& limits);

// Sum of MoveTimeS over consecutive waypoints (0 for fewer than two).
double PathTimeS(std::span<const Joints> waypoints, const JointLimits& limits);

// The input checks of the functions below (and of blend.h): INVALID_ARGUMENT naming the field for
// no waypoints, a non-finite joint value, invalid limits, non-finite start_time_s or
// sample_dt_s <= 0.
absl::Status ValidateTimingInput(std::span<const Joints> waypoints, const JointLimits& limits,
                                 double start_time_s, double sample_dt_s);

// Samples of the timed path: for each segment, samples every `sample_dt_s` from its start, plus
// every waypoint exactly (the first at start_time_s, the last at start_time_s + PathTimeS).
// Times are strictly increasing: a waypoint equal to the one before it (a zero-length segment)
// is merged with it. INVALID_ARGUMENT naming the field: no waypoints, a non-finite joint value,
// invalid limits, sample_dt_s <= 0 or non-finite start_time_s, or more than 10 million samples.
absl::StatusOr<std::vector<TimedJoints>> TimeParameterize(std::span<const Joints> waypoints,
                                                          const JointLimits& limits,
                                                          double start_time_s,
                                                          double sample_dt_s);

// A dense polyline (a cut stroke) timed along its joint-space arc length without stopping at its
// waypoints: on segment k the path speed keeps every joint within speed_fraction[k] times its
// velocity limit, the path accelerates within the acceleration limits along the segment's own
// direction, and the arm is at rest at both ends and at every waypoint index in `stops`. It is
// the fastest such profile (forward and backward passes over the waypoint speeds, then a
// trapezoid per segment). Corners are passed at speed, where the joint velocity turns instantly;
// that suits dense, nearly straight paths such as a cut stroke (Cartesian steps of 5 mm), not
// transits. Samples: every waypoint at its time and a grid of sample_dt_s per segment, strictly
// increasing (repeated waypoints merged). Errors as TimeParameterize, and INVALID_ARGUMENT for
// speed_fraction without one value in (0, 1] per segment or a stop index out of range.
absl::StatusOr<std::vector<TimedJoints>> TimeParameterizeAlongPath(
    std::span<const Joints> waypoints, const JointLimits& limits,
    std::span<const double> speed_fraction, std::span<const int> stops, double start_time_s,
    double sample_dt_s);

// TimeParameterizeAlongPath at the full limits on every segment, stopping at the ends only.
absl::StatusOr<std::vector<TimedJoints>> TimeParameterizeStroke(std::span<const Joints> waypoints,
                                                                const JointLimits& limits,
                                                                double start_time_s,
                                                                double sample_dt_s);

// Position of the timed move a -> b at time t in [0, MoveTimeS(a, b)] after its start (clamped
// outside). Exposed for tests and for executors that interpolate themselves.
Joints MoveStateAt(const Joints& a, const Joints& b, const JointLimits& limits, double t);

}  // namespace vb::plan
