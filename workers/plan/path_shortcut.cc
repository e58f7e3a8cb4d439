// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/path_shortcut.h"

#include <algorithm>
#include <cstddef>
#include <random>
#include <span>
#include <utility>
#include <vector>

#include "workers/plan/time_parameterization.h"

namespace vb::plan {
namespace {

// Removes waypoints greedily: from each kept waypoint, jump to the farthest later one whose
// straight segment is free and faster than the waypoints it skips. Returns shortcuts taken.
int GreedySkip(CollisionChecker& checker, const JointLimits& limits, double max_step_m,
               const Deadline& deadline, std::vector<Joints>& w) {
  int taken = 0;
  for (size_t i = 0; i + 2 < w.size(); ++i) {
    for (size_t j = w.size() - 1; j >= i + 2; --j) {
      if (deadline.Expired()) return taken;
      const double via = PathTimeS(std::span<const Joints>(w).subspan(i, j - i + 1), limits);
      if (MoveTimeS(w[i], w[j], limits) >= via) continue;
      if (checker.IsMotionFree(w[i], w[j], max_step_m)) {
        w.erase(w.begin() + static_cast<std::ptrdiff_t>(i) + 1, w.begin() + static_cast<std::ptrdiff_t>(j));
        ++taken;
        break;
      }
    }
  }
  return taken;
}

}  // namespace

int ShortcutPath(CollisionChecker& checker, const JointLimits& limits, double max_step_m,
                 int rounds, uint64_t seed, const Deadline& deadline,
                 std::vector<Joints>& waypoints) {
  std::vector<Joints>& w = waypoints;
  if (w.size() < 3) return 0;
  int taken = GreedySkip(checker, limits, max_step_m, deadline, w);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Per path: cumulative joint-space length at each waypoint and the time of each segment;
  // recomputed only when a shortcut is taken, so a rejected round costs a few MoveTimeS.
  std::vector<double> cumulative, seg_time;
  double path_time = 0.0;
  auto measure = [&] {
    cumulative.assign(w.size(), 0.0);
    seg_time.assign(w.size() - 1, 0.0);
    path_time = 0.0;
    for (size_t k = 1; k < w.size(); ++k) {
      cumulative[k] = cumulative[k - 1] + (w[k] - w[k - 1]).norm();
      seg_time[k - 1] = MoveTimeS(w[k - 1], w[k], limits);
      path_time += seg_time[k - 1];
    }
  };
  measure();
  std::vector<Joints> candidate;
  for (int round = 0; round < rounds && w.size() >= 3; ++round) {
    if (deadline.Expired()) break;
    // Two points drawn uniformly by joint-space length along the path; the segment between
    // them replaces what lies between (OMPL's PathSimplifier::shortcutPath does the same).
    const double length = cumulative.back();
    double u = unit(rng) * length, v = unit(rng) * length;
    if (u > v) std::swap(u, v);
    auto locate = [&](double s, size_t& seg, Joints& q) {
      seg = static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), s) -
                                cumulative.begin());
      seg = std::clamp<size_t>(seg, 1, w.size() - 1) - 1;  // segment seg: w[seg] -> w[seg + 1]
      const double len = cumulative[seg + 1] - cumulative[seg];
      const double f = len > 0 ? std::clamp((s - cumulative[seg]) / len, 0.0, 1.0) : 0.0;
      q = w[seg] + f * (w[seg + 1] - w[seg]);
    };
    size_t i = 0, j = 0;
    Joints qu, qv;
    locate(u, i, qu);
    locate(v, j, qv);
    if (i == j) continue;  // both on one straight segment: nothing to gain
    // Time of w[0..i], qu, qv, w[j+1..]: the segments i..j are replaced by three.
    double replaced = 0.0;
    for (size_t k = i; k <= j; ++k) replaced += seg_time[k];
    const double joined = MoveTimeS(w[i], qu, limits) + MoveTimeS(qu, qv, limits) +
                          MoveTimeS(qv, w[j + 1], limits);
    if (joined >= replaced - 1e-9) continue;
    // The new joining segment first (it is the one likely to fail), then the two remnants of
    // old segments: sub-segments of checked segments, but sampled at other points, so they are
    // checked again to keep the contract that every output segment passed IsMotionFree.
    if (!checker.IsMotionFree(qu, qv, max_step_m)) continue;
    if (!checker.IsMotionFree(w[i], qu, max_step_m)) continue;
    if (!checker.IsMotionFree(qv, w[j + 1], max_step_m)) continue;
    candidate.assign(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(i) + 1);
    for (const Joints* q : {&qu, &qv}) {
      if (!SameWaypoint(candidate.back(), *q)) candidate.push_back(*q);
    }
    for (size_t k = j + 1; k < w.size(); ++k) {
      if (!SameWaypoint(candidate.back(), w[k])) candidate.push_back(w[k]);
    }
    w.swap(candidate);
    measure();
    ++taken;
  }
  taken += GreedySkip(checker, limits, max_step_m, deadline, w);
  return taken;
}

}  // namespace vb::plan
