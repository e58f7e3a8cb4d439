// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/time_parameterization.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"

namespace vb::plan {
namespace {

constexpr int64_t kMaxSamples = 10'000'000;

// The profile of the path parameter s in [0, 1] of one move. Moves shorter than this (in every
// joint) are treated as no move at all: below it the profile is numerically meaningless.
constexpr double kZeroMoveRad = 1e-12;

struct Profile {
  double accel = 0.0;     // A, 1/s^2
  double peak = 0.0;      // peak ds/dt reached (V when trapezoidal)
  double t_ramp = 0.0;    // duration of the acceleration (= deceleration) phase
  double t_total = 0.0;
};

// The parameter covers distance 1 with ramps up and down at acceleration `acc`, cruising at `v`:
// triangular when v is never reached.
Profile ProfileOf(double v, double acc) {
  Profile p;
  p.accel = acc;
  if (v * v / acc >= 1.0) {
    p.t_ramp = std::sqrt(1.0 / acc);
    p.peak = acc * p.t_ramp;
    p.t_total = 2.0 * p.t_ramp;
  } else {
    p.peak = v;
    p.t_ramp = v / acc;
    p.t_total = 1.0 / v + v / acc;
  }
  return p;
}

Profile MakeProfile(const Joints& a, const Joints& b, const JointLimits& limits) {
  double v = std::numeric_limits<double>::infinity();
  double acc = std::numeric_limits<double>::infinity();
  bool moves = false;
  for (int i = 0; i < 6; ++i) {
    const double d = std::abs(b[i] - a[i]);
    if (!(d > kZeroMoveRad)) continue;
    moves = true;
    v = std::min(v, limits.max_velocity[i] / d);
    acc = std::min(acc, limits.max_acceleration[i] / d);
  }
  if (!moves) return Profile{};
  return ProfileOf(v, acc);
}

double ParameterAt(const Profile& p, double t) {
  if (p.t_total <= 0.0) return 1.0;
  if (t <= 0.0) return 0.0;
  if (t >= p.t_total) return 1.0;
  const double ramp_s = 0.5 * p.accel * p.t_ramp * p.t_ramp;
  if (t < p.t_ramp) return 0.5 * p.accel * t * t;
  const double t_down = p.t_total - p.t_ramp;
  if (t <= t_down) return ramp_s + p.peak * (t - p.t_ramp);
  const double left = p.t_total - t;
  return 1.0 - 0.5 * p.accel * left * left;
}

}  // namespace

double MoveTimeS(const Joints& a, const Joints& b, const JointLimits& limits) {
  return MakeProfile(a, b, limits).t_total;
}

double PathTimeS(std::span<const Joints> waypoints, const JointLimits& limits) {
  double total = 0.0;
  for (size_t i = 1; i < waypoints.size(); ++i) total += MoveTimeS(waypoints[i - 1], waypoints[i], limits);
  return total;
}

Joints MoveStateAt(const Joints& a, const Joints& b, const JointLimits& limits, double t) {
  const Profile p = MakeProfile(a, b, limits);
  const double s = ParameterAt(p, t);
  if (s >= 1.0) return b;  // exact at the end, not a + 1.0 * (b - a)
  return a + s * (b - a);
}

absl::Status ValidateTimingInput(std::span<const Joints> waypoints, const JointLimits& limits,
                        double start_time_s, double sample_dt_s) {
  if (waypoints.empty()) return absl::InvalidArgumentError("time parameterisation: waypoints: empty");
  for (size_t k = 0; k < waypoints.size(); ++k) {
    if (!waypoints[k].allFinite()) {
      return absl::InvalidArgumentError(
          absl::StrCat("time parameterisation: waypoints[", k, "]: non-finite joint value"));
    }
  }
  if (absl::Status s = limits.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("time parameterisation: ", s.message()));
  }
  if (!std::isfinite(start_time_s)) {
    return absl::InvalidArgumentError("time parameterisation: start_time_s: must be finite");
  }
  if (!(sample_dt_s > 0.0) || !std::isfinite(sample_dt_s)) {
    return absl::InvalidArgumentError("time parameterisation: sample_dt_s: must be finite and > 0");
  }
  return absl::OkStatus();
}

absl::StatusOr<std::vector<TimedJoints>> TimeParameterize(std::span<const Joints> waypoints,
                                                          const JointLimits& limits,
                                                          double start_time_s,
                                                          double sample_dt_s) {
  if (absl::Status s = ValidateTimingInput(waypoints, limits, start_time_s, sample_dt_s); !s.ok()) return s;
  std::vector<Profile> profiles;
  profiles.reserve(waypoints.size());
  double expected = 1.0;
  for (size_t k = 1; k < waypoints.size(); ++k) {
    profiles.push_back(MakeProfile(waypoints[k - 1], waypoints[k], limits));
    expected += std::ceil(profiles.back().t_total / sample_dt_s) + 1.0;
  }
  if (expected > static_cast<double>(kMaxSamples)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "time parameterisation: sample_dt_s: would give more than ", kMaxSamples, " samples"));
  }

  std::vector<TimedJoints> samples;
  samples.reserve(static_cast<size_t>(expected));
  samples.push_back({start_time_s, waypoints[0]});
  double t0 = start_time_s;
  for (size_t k = 1; k < waypoints.size(); ++k) {
    const Profile& p = profiles[k - 1];
    if (p.t_total <= 0.0) continue;  // zero-length segment: the waypoint is already there
    const Joints& a = waypoints[k - 1];
    const Joints& b = waypoints[k];
    // Samples strictly inside the segment, on the segment's own grid; the grid point closer than
    // a thousandth of a step to the end is dropped so times stay strictly increasing.
    for (int64_t j = 1;; ++j) {
      const double tau = static_cast<double>(j) * sample_dt_s;
      if (tau >= p.t_total - 1e-3 * sample_dt_s) break;
      samples.push_back({t0 + tau, a + ParameterAt(p, tau) * (b - a)});
    }
    t0 += p.t_total;
    samples.push_back({t0, b});
  }
  return samples;
}

absl::StatusOr<std::vector<TimedJoints>> TimeParameterizeStroke(std::span<const Joints> waypoints,
                                                                const JointLimits& limits,
                                                                double start_time_s,
                                                                double sample_dt_s) {
  if (absl::Status s = ValidateTimingInput(waypoints, limits, start_time_s, sample_dt_s); !s.ok()) return s;
  // Arc length fraction of each segment, then the parameter's limits: on segment i, joint j moves
  // d_ij per unit of the parameter's fraction f_i, so ds/dt <= vmax_j f_i / d_ij (and likewise
  // for the acceleration).
  std::vector<double> start_fraction = {0.0};
  double total = 0.0;
  for (size_t k = 1; k < waypoints.size(); ++k) total += (waypoints[k] - waypoints[k - 1]).norm();
  if (!(total > kZeroMoveRad)) return std::vector<TimedJoints>{{start_time_s, waypoints[0]}};
  double v = std::numeric_limits<double>::infinity(), acc = v;
  for (size_t k = 1; k < waypoints.size(); ++k) {
    const Joints d = waypoints[k] - waypoints[k - 1];
    const double f = d.norm() / total;
    start_fraction.push_back(start_fraction.back() + f);
    for (int j = 0; j < 6; ++j) {
      if (!(std::abs(d[j]) > kZeroMoveRad)) continue;
      v = std::min(v, limits.max_velocity[j] * f / std::abs(d[j]));
      acc = std::min(acc, limits.max_acceleration[j] * f / std::abs(d[j]));
    }
  }
  const Profile p = ProfileOf(v, acc);
  if (p.t_total / sample_dt_s + waypoints.size() > static_cast<double>(kMaxSamples)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "time parameterisation: sample_dt_s: would give more than ", kMaxSamples, " samples"));
  }
  // The time at which the parameter reaches fraction x (the inverse of ParameterAt).
  auto time_at = [&](double x) {
    const double ramp_s = 0.5 * p.accel * p.t_ramp * p.t_ramp;
    if (x <= ramp_s) return std::sqrt(2.0 * x / p.accel);
    if (x <= 1.0 - ramp_s) return p.t_ramp + (x - ramp_s) / p.peak;
    return p.t_total - std::sqrt(std::max(0.0, 2.0 * (1.0 - x) / p.accel));
  };
  auto position_at = [&](double x) {
    const size_t k = std::min<size_t>(
        waypoints.size() - 1,
        std::upper_bound(start_fraction.begin(), start_fraction.end(), x) - start_fraction.begin());
    const double f0 = start_fraction[k - 1], f1 = start_fraction[k];
    const double u = f1 > f0 ? std::clamp((x - f0) / (f1 - f0), 0.0, 1.0) : 1.0;
    return Joints(waypoints[k - 1] + u * (waypoints[k] - waypoints[k - 1]));
  };
  // Waypoint times and grid samples merged in time order, strictly increasing.
  std::vector<TimedJoints> samples = {{start_time_s, waypoints[0]}};
  double next_grid = sample_dt_s;
  for (size_t k = 1; k < waypoints.size(); ++k) {
    const double t_k = k + 1 == waypoints.size() ? p.t_total : time_at(start_fraction[k]);
    for (; next_grid < t_k - 1e-3 * sample_dt_s; next_grid += sample_dt_s) {
      // A grid time just before the previous waypoint's time has been passed already.
      if (start_time_s + next_grid <= samples.back().t + 1e-3 * sample_dt_s) continue;
      samples.push_back({start_time_s + next_grid, position_at(ParameterAt(p, next_grid))});
    }
    if (start_time_s + t_k > samples.back().t) samples.push_back({start_time_s + t_k, waypoints[k]});
  }
  return samples;
}

}  // namespace vb::plan
