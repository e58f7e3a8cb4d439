// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/blend.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <map>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "core/status_macros.h"

namespace vb::plan {
namespace {

constexpr double kZeroMoveRad = 1e-12;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int64_t kMaxSamples = 10'000'000;

// Linear segments with parabolic blends through w[0..n] (n >= 1), starting and ending at rest.
struct Run {
  std::vector<Joints> w;
  std::vector<double> T;     // n linear durations (between the via times tau)
  std::vector<Joints> v;     // n segment velocities
  std::vector<double> tb;    // n + 1 blend durations (0 and n: from / to rest along the segment)
  std::vector<Joints> acc;   // n + 1 blend accelerations
  std::vector<double> tau;   // n + 1 via times from the run's start
  double duration = 0.0;

  int n() const { return static_cast<int>(T.size()); }

  void Derive(const JointLimits& limits) {
    const int m = n();
    v.resize(m);
    tb.assign(m + 1, 0.0);
    acc.assign(m + 1, Joints::Zero());
    tau.assign(m + 1, 0.0);
    for (int k = 0; k < m; ++k) v[k] = (w[k + 1] - w[k]) / T[k];
    for (int k = 0; k <= m; ++k) {
      const Joints dv = (k < m ? v[k] : Joints::Zero()) - (k > 0 ? v[k - 1] : Joints::Zero());
      double t = 0.0;
      for (int j = 0; j < 6; ++j) t = std::max(t, std::abs(dv[j]) / limits.max_acceleration[j]);
      tb[k] = t;
      if (t > 0) acc[k] = dv / t;
    }
    tau[0] = 0.5 * tb[0];
    for (int k = 0; k < m; ++k) tau[k + 1] = tau[k] + T[k];
    duration = tau[m] + 0.5 * tb[m];
  }

  // Largest joint distance of the blend's middle from via k (|dv| tb / 8).
  double Deviation(int k) const {
    const Joints dv = (k < n() ? v[k] : Joints::Zero()) - (k > 0 ? v[k - 1] : Joints::Zero());
    return dv.cwiseAbs().maxCoeff() * tb[k] / 8.0;
  }

  Joints At(double t) const {
    const int m = n();
    if (t <= 0.0) return w[0];
    if (t >= duration) return w[m];
    for (int k = 0; k <= m; ++k) {
      const double lo = tau[k] - 0.5 * tb[k];
      if (t < lo) return w[k - 1] + v[k - 1] * (t - tau[k - 1]);  // k >= 1 since lo(0) = 0
      if (t <= tau[k] + 0.5 * tb[k]) {
        const Joints v_in = k > 0 ? v[k - 1] : Joints::Zero();
        const double u = t - lo;
        return w[k] + v_in * (t - tau[k]) + 0.5 * u * u * acc[k];
      }
    }
    return w[m];
  }
};

// The durations: from the velocity bound, grown where blends overlap or a via's deviation exceeds
// max_dev[k] (k = 1..n-1); a few local rounds, then one uniform scaling that satisfies the rest.
Run Solve(std::span<const Joints> w, const JointLimits& limits, std::span<const double> max_dev) {
  Run r;
  r.w.assign(w.begin(), w.end());
  const int m = static_cast<int>(w.size()) - 1;
  r.T.assign(m, 0.0);
  for (int k = 0; k < m; ++k) {
    for (int j = 0; j < 6; ++j)
      r.T[k] = std::max(r.T[k], std::abs(w[k + 1][j] - w[k][j]) / limits.max_velocity[j]);
  }
  // ratio[k] > 1: segment k (or via k's neighbours) must slow down by sqrt(ratio).
  auto ratios = [&](std::vector<double>& factor) {
    factor.assign(m, 1.0);
    double worst = 1.0;
    for (int k = 0; k < m; ++k) {
      const double ratio = 0.5 * (r.tb[k] + r.tb[k + 1]) / r.T[k];
      factor[k] = std::max(factor[k], ratio);
      worst = std::max(worst, ratio);
    }
    for (int k = 1; k < m; ++k) {
      if (!std::isfinite(max_dev[k])) continue;
      const double dev = r.Deviation(k);
      if (dev <= max_dev[k]) continue;
      const double ratio = max_dev[k] > 0 ? dev / max_dev[k] : kInf;
      factor[k - 1] = std::max(factor[k - 1], ratio);
      factor[k] = std::max(factor[k], ratio);
      worst = std::max(worst, ratio);
    }
    return worst;
  };
  std::vector<double> factor;
  bool feasible = false;
  for (int round = 0; round < 30 && !feasible; ++round) {
    r.Derive(limits);
    feasible = ratios(factor) <= 1.0 + 1e-12;
    if (feasible) break;
    for (int k = 0; k < m; ++k)
      if (factor[k] > 1.0) r.T[k] *= std::sqrt(factor[k]) * (1.0 + 1e-9);
  }
  if (!feasible) {
    r.Derive(limits);
    const double worst = ratios(factor);
    if (worst > 1.0 && std::isfinite(worst)) {
      for (double& t : r.T) t *= std::sqrt(worst) * (1.0 + 1e-9);
      r.Derive(limits);
    }
  }
  // Coordinate descent: shorten each segment as far as the constraints allow (bisection between
  // its velocity bound and its current, feasible, duration), a few sweeps.
  const std::vector<double> lower = [&] {
    std::vector<double> l(m, 0.0);
    for (int k = 0; k < m; ++k)
      for (int j = 0; j < 6; ++j)
        l[k] = std::max(l[k], std::abs(w[k + 1][j] - w[k][j]) / limits.max_velocity[j]);
    return l;
  }();
  for (int sweep = 0; sweep < 8 && m > 1; ++sweep) {
    double saved = 0.0;
    for (int k = 0; k < m; ++k) {
      const double r_before = r.T[k];
      double lo = lower[k], hi = r_before;
      if (!(hi > lo * (1.0 + 1e-9))) continue;
      for (int it = 0; it < 24; ++it) {
        const double mid = 0.5 * (lo + hi);
        r.T[k] = mid;
        r.Derive(limits);
        (ratios(factor) <= 1.0 + 1e-12 ? hi : lo) = mid;
      }
      saved += r_before - hi;
      r.T[k] = hi;
    }
    r.Derive(limits);
    if (saved < 1e-4 * r.duration) break;
  }
  return r;
}

// The path as runs between stops (stop[0] and stop.back() are true): each run blended, or split
// into rest-to-rest moves where blending it would be slower.
std::vector<Run> Layout(std::span<const Joints> w, const JointLimits& limits,
                        std::vector<bool>& stop, std::span<const double> max_dev) {
  std::vector<Run> runs;
  size_t a = 0;
  for (size_t b = 1; b < w.size(); ++b) {
    if (!stop[b]) continue;
    const auto part = w.subspan(a, b - a + 1);
    Run run = Solve(part, limits, max_dev.subspan(a, b - a + 1));
    if (part.size() > 2 && run.duration > PathTimeS(part, limits)) {
      const double none[2] = {kInf, kInf};
      for (size_t k = a; k < b; ++k) {
        if (k > a) stop[k] = true;
        runs.push_back(Solve(w.subspan(k, 2), limits, none));
      }
    } else {
      runs.push_back(std::move(run));
    }
    a = b;
  }
  return runs;
}

// The exact bits of a chord's two ends.
using ChordKey = std::array<uint64_t, 12>;
ChordKey KeyOf(const Joints& a, const Joints& b) {
  ChordKey key;
  std::memcpy(key.data(), a.data(), 6 * sizeof(double));
  std::memcpy(key.data() + 6, b.data(), 6 * sizeof(double));
  return key;
}

// Waypoints with repeated ones merged.
std::vector<Joints> Distinct(std::span<const Joints> waypoints) {
  std::vector<Joints> w = {waypoints.front()};
  for (size_t k = 1; k < waypoints.size(); ++k)
    if ((waypoints[k] - w.back()).cwiseAbs().maxCoeff() > kZeroMoveRad) w.push_back(waypoints[k]);
  return w;
}

}  // namespace

absl::Status BlendOptions::Validate() const {
  if (!(max_step_m > 0) || !std::isfinite(max_step_m))
    return absl::InvalidArgumentError("blend options: max_step_m: must be finite and > 0");
  if (max_shrinks < 0 || max_shrinks > 30)
    return absl::InvalidArgumentError("blend options: max_shrinks: must be in [0, 30]");
  return absl::OkStatus();
}

double BlendedPathTimeS(std::span<const Joints> waypoints, const JointLimits& limits) {
  if (waypoints.size() < 2) return 0.0;
  const std::vector<Joints> w = Distinct(waypoints);
  if (w.size() < 2) return 0.0;
  std::vector<bool> stop(w.size(), false);
  stop.front() = stop.back() = true;
  const std::vector<double> max_dev(w.size(), kInf);
  double total = 0.0;
  for (const Run& run : Layout(w, limits, stop, max_dev)) total += run.duration;
  return total;
}

absl::StatusOr<BlendedPath> TimeParameterizeBlended(std::span<const Joints> waypoints,
                                                    const JointLimits& limits,
                                                    CollisionChecker* checker,
                                                    const BlendOptions& options,
                                                    double start_time_s, double sample_dt_s) {
  VB_RETURN_IF_ERROR(ValidateTimingInput(waypoints, limits, start_time_s, sample_dt_s));
  VB_RETURN_IF_ERROR(options.Validate());
  BlendedPath out;
  const std::vector<Joints> w = Distinct(waypoints);
  if (w.size() < 2) {
    out.samples = {{start_time_s, waypoints.front()}};
    return out;
  }
  const int points = static_cast<int>(w.size());
  out.vias = points - 2;
  if (PathTimeS(w, limits) / sample_dt_s + points > static_cast<double>(kMaxSamples)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "time parameterisation: sample_dt_s: would give more than ", kMaxSamples, " samples"));
  }
  std::vector<bool> stop(points, false);
  stop.front() = stop.back() = true;
  std::vector<double> max_dev(points, kInf);
  // Bisection on the size (deviation) of each blend that collided: between the largest size
  // found free (ok) and the smallest found colliding (bad); a blend out of steps keeps its
  // largest free size, and stops if that collides too (the neighbouring blends change the
  // segments' speeds, so a size found free may not stay free).
  std::vector<int> steps(points, 0);
  std::vector<double> ok(points, 0.0), bad(points, kInf);
  std::vector<bool> last_try(points, false);
  const int64_t checks_before = checker != nullptr ? checker->checks() : 0;
  // Chords already checked in an earlier round (a run whose stops and blend bounds did not
  // change is laid out again bit for bit): the checker's answer, which is deterministic.
  std::map<ChordKey, bool> chord_free;
  // Every round takes a bisection step, settles a blend or stops at a via, so this ends.
  for (;;) {
    const std::vector<Run> runs = Layout(w, limits, stop, max_dev);
    // Samples on each run's own grid, the run's end (a stop) exactly.
    out.samples = {{start_time_s, w.front()}};
    std::vector<size_t> run_first_sample;  // index of each run's start sample
    double t0 = start_time_s;
    for (const Run& run : runs) {
      run_first_sample.push_back(out.samples.size() - 1);
      for (int64_t j = 1;; ++j) {
        const double tau = static_cast<double>(j) * sample_dt_s;
        if (tau >= run.duration - 1e-3 * sample_dt_s) break;
        out.samples.push_back({t0 + tau, run.At(tau)});
      }
      t0 += run.duration;
      out.samples.push_back({t0, run.w.back()});
    }
    out.duration_s = t0 - start_time_s;

    // The chords that overlap each interior blend (checked, unless there is no checker).
    std::vector<int> colliding;  // global via indices
    out.blend_chords.clear();
    int via_base = 0;
    for (size_t r = 0; r < runs.size(); ++r) {
      const Run& run = runs[r];
      const double run_t0 = out.samples[run_first_sample[r]].t;
      const size_t first = run_first_sample[r];
      const size_t last = r + 1 < runs.size() ? run_first_sample[r + 1] : out.samples.size() - 1;
      for (int k = 1; k < run.n(); ++k) {
        if (!(run.tb[k] > 0)) continue;
        const double lo = run_t0 + run.tau[k] - 0.5 * run.tb[k];
        const double hi = run_t0 + run.tau[k] + 0.5 * run.tb[k];
        bool free = true;
        for (size_t i = first; i < last; ++i) {
          if (out.samples[i + 1].t <= lo || out.samples[i].t >= hi) continue;
          if (out.blend_chords.empty() || out.blend_chords.back() < static_cast<int>(i))
            out.blend_chords.push_back(static_cast<int>(i));
          if (checker != nullptr && free) {
            const ChordKey key = KeyOf(out.samples[i].q, out.samples[i + 1].q);
            const auto [it, inserted] = chord_free.try_emplace(key, false);
            if (inserted) {
              it->second = checker->IsMotionFree(out.samples[i].q, out.samples[i + 1].q,
                                                 options.max_step_m);
            }
            free = it->second;
          }
        }
        if (!free) colliding.push_back(via_base + k);
      }
      via_base += run.n();
    }
    if (checker == nullptr) break;
    // Deviations are read from the current layout.
    via_base = 0;
    std::vector<double> deviation(points, 0.0);
    for (const Run& run : runs) {
      for (int k = 1; k < run.n(); ++k) deviation[via_base + k] = run.Deviation(k);
      via_base += run.n();
    }
    std::vector<bool> collides(points, false);
    for (int g : colliding) collides[g] = true;
    bool changed = false;
    for (int g = 1; g + 1 < points; ++g) {
      if (stop[g]) continue;
      if (collides[g]) {
        changed = true;
        bad[g] = std::min(bad[g], deviation[g]);
        if (last_try[g] || !(deviation[g] > 1e-9)) {
          stop[g] = true;
        } else if (steps[g] >= options.max_shrinks) {
          if (ok[g] > 0) {
            max_dev[g] = ok[g];
            last_try[g] = true;
          } else {
            stop[g] = true;
          }
        } else {
          max_dev[g] = 0.5 * (ok[g] + bad[g]);
          ++steps[g];
          ++out.shrinks;
        }
      } else if (std::isfinite(bad[g]) && !last_try[g] && steps[g] < options.max_shrinks) {
        // Free after a collision: try a larger blend, halfway to the smallest colliding one.
        ok[g] = std::max(ok[g], deviation[g]);
        max_dev[g] = 0.5 * (ok[g] + bad[g]);
        ++steps[g];
        changed = true;
      }
    }
    if (!changed) break;
  }
  for (int k = 1; k + 1 < points; ++k) out.stops += stop[k] ? 1 : 0;
  if (checker != nullptr) out.checks = checker->checks() - checks_before;
  return out;
}

}  // namespace vb::plan
