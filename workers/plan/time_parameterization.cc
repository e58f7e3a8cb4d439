// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/time_parameterization.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"

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

absl::StatusOr<std::vector<TimedJoints>> TimeParameterizeAlongPath(
    std::span<const Joints> waypoints, const JointLimits& limits,
    std::span<const double> speed_fraction, std::span<const int> stops, double start_time_s,
    double sample_dt_s) {
  VB_RETURN_IF_ERROR(ValidateTimingInput(waypoints, limits, start_time_s, sample_dt_s));
  const size_t n = waypoints.size() - 1;
  if (speed_fraction.size() != n) {
    return absl::InvalidArgumentError(absl::StrCat("time parameterisation: speed_fraction: ",
                                                   speed_fraction.size(), " values for ", n,
                                                   " segments"));
  }
  for (size_t k = 0; k < n; ++k) {
    if (!(speed_fraction[k] > 0.0) || !(speed_fraction[k] <= 1.0)) {
      return absl::InvalidArgumentError(
          absl::StrCat("time parameterisation: speed_fraction[", k, "]: must be in (0, 1]"));
    }
  }
  // Per segment: length, and the path speed and acceleration that keep every joint in its limits.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> length(n, 0.0), v_max(n, kInf), a_max(n, kInf);
  for (size_t k = 0; k < n; ++k) {
    const Joints d = waypoints[k + 1] - waypoints[k];
    if (!(d.cwiseAbs().maxCoeff() > kZeroMoveRad)) continue;  // merged with its start
    length[k] = d.norm();
    for (int j = 0; j < 6; ++j) {
      if (!(std::abs(d[j]) > kZeroMoveRad)) continue;
      v_max[k] = std::min(v_max[k], limits.max_velocity[j] * length[k] / std::abs(d[j]));
      a_max[k] = std::min(a_max[k], limits.max_acceleration[j] * length[k] / std::abs(d[j]));
    }
    v_max[k] *= speed_fraction[k];
  }
  // Path speed at each waypoint: 0 at the ends and stops, within both neighbours' caps, then
  // reachable from the previous waypoint (forward) and able to stop in time (backward).
  std::vector<double> v(n + 1, kInf);
  v[0] = v[n] = 0.0;
  for (int k : stops) {
    if (k < 0 || static_cast<size_t>(k) > n) {
      return absl::InvalidArgumentError(
          absl::StrCat("time parameterisation: stops: index ", k, " outside [0, ", n, "]"));
    }
    v[k] = 0.0;
  }
  for (size_t k = 0; k < n; ++k) {
    v[k] = std::min(v[k], v_max[k]);
    v[k + 1] = std::min(v[k + 1], v_max[k]);
  }
  for (size_t k = 0; k < n; ++k) {
    if (length[k] > 0) v[k + 1] = std::min(v[k + 1], std::sqrt(v[k] * v[k] + 2 * a_max[k] * length[k]));
    else v[k + 1] = std::min(v[k + 1], v[k]);
  }
  for (size_t k = n; k-- > 0;) {
    if (length[k] > 0) v[k] = std::min(v[k], std::sqrt(v[k + 1] * v[k + 1] + 2 * a_max[k] * length[k]));
    else v[k] = std::min(v[k], v[k + 1]);
  }
  // One trapezoid per segment from v[k] to v[k + 1], peak within the cap.
  struct Piece {
    double v0 = 0, peak = 0, accel = 0, t_up = 0, t_cruise = 0, t_down = 0, d_up = 0;
    double Total() const { return t_up + t_cruise + t_down; }
    double DistanceAt(double t) const {
      if (t <= t_up) return v0 * t + 0.5 * accel * t * t;
      if (t <= t_up + t_cruise) return d_up + peak * (t - t_up);
      const double u = t - t_up - t_cruise;
      return d_up + peak * t_cruise + peak * u - 0.5 * accel * u * u;
    }
  };
  std::vector<Piece> pieces(n);
  double total_t = 0.0;
  for (size_t k = 0; k < n; ++k) {
    if (!(length[k] > 0)) continue;
    Piece& p = pieces[k];
    const double a = a_max[k], v0 = v[k], v1 = v[k + 1];
    p.v0 = v0;
    p.accel = a;
    p.peak = std::max({std::min(v_max[k], std::sqrt(a * length[k] + 0.5 * (v0 * v0 + v1 * v1))),
                       v0, v1});
    p.t_up = (p.peak - v0) / a;
    p.t_down = (p.peak - v1) / a;
    p.d_up = 0.5 * (p.peak * p.peak - v0 * v0) / a;
    const double d_down = 0.5 * (p.peak * p.peak - v1 * v1) / a;
    p.t_cruise = std::max(0.0, length[k] - p.d_up - d_down) / p.peak;
    total_t += p.Total();
  }
  if (total_t / sample_dt_s + 2.0 * waypoints.size() > static_cast<double>(kMaxSamples)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "time parameterisation: sample_dt_s: would give more than ", kMaxSamples, " samples"));
  }
  std::vector<TimedJoints> samples = {{start_time_s, waypoints[0]}};
  double t0 = start_time_s;
  for (size_t k = 0; k < n; ++k) {
    const Piece& p = pieces[k];
    const double t_k = p.Total();
    if (!(length[k] > 0) || !(t_k > 0)) continue;
    const Joints& a = waypoints[k];
    const Joints d = waypoints[k + 1] - a;
    for (int64_t j = 1;; ++j) {
      const double tau = static_cast<double>(j) * sample_dt_s;
      if (tau >= t_k - 1e-3 * sample_dt_s) break;
      const double x = std::clamp(p.DistanceAt(tau) / length[k], 0.0, 1.0);
      samples.push_back({t0 + tau, a + x * d});
    }
    t0 += t_k;
    samples.push_back({t0, waypoints[k + 1]});
  }
  return samples;
}

absl::StatusOr<std::vector<TimedJoints>> TimeParameterizeStroke(std::span<const Joints> waypoints,
                                                                const JointLimits& limits,
                                                                double start_time_s,
                                                                double sample_dt_s) {
  const std::vector<double> full(waypoints.empty() ? 0 : waypoints.size() - 1, 1.0);
  return TimeParameterizeAlongPath(waypoints, limits, full, {}, start_time_s, sample_dt_s);
}

}  // namespace vb::plan
