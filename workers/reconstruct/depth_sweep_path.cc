// SPDX-License-Identifier: Apache-2.0
// Step 3 of the depth sweep (depth_sweep.h): the Viterbi path of one stretch's depths.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>

#include "workers/reconstruct/depth_sweep_internal.h"
#include "workers/reconstruct/image_probes.h"

namespace vb::reconstruct::depth_sweep_internal {
namespace {

// A (sample, depth) outside the volume, or seen by no other view: never on the chosen path
// where any other is possible, but finite so that the dynamic programme stays well defined.
constexpr double kExcluded = 1e4;

// The ray parameters [enter, leave] of C + t d inside the box, t >= 0.05; nullopt if none.
std::optional<std::pair<double, double>> RayInBox(const Eigen::Vector3d& c,
                                                  const Eigen::Vector3d& d,
                                                  const Eigen::AlignedBox3d& box) {
  double lo = 0.05, hi = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (c[a] < box.min()[a] || c[a] > box.max()[a]) return std::nullopt;
      continue;
    }
    double t0 = (box.min()[a] - c[a]) / d[a], t1 = (box.max()[a] - c[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
  }
  if (!(lo < hi)) return std::nullopt;
  return std::make_pair(lo, hi);
}

}  // namespace

StretchDepths SweepStretch(const std::vector<Eigen::Vector3d>& rays, int v,
                           const std::vector<View2D>& views, const RigCalibration& rig,
                           const WorkingVolume& volume, const DepthSweepOptions& options) {
  const int n = static_cast<int>(rays.size());
  const Eigen::Vector3d c = rig.cameras[v].CentreInPlatform();
  std::vector<std::optional<std::pair<double, double>>> range(n);
  double t_lo = std::numeric_limits<double>::infinity(), t_hi = 0.0;
  int middle = -1;
  for (int i = 0; i < n; ++i) {
    range[i] = RayInBox(c, rays[i], volume.box);
    if (!range[i]) continue;
    t_lo = std::min(t_lo, range[i]->first);
    t_hi = std::max(t_hi, range[i]->second);
    if (middle < 0 || std::abs(i - n / 2) < std::abs(middle - n / 2)) middle = i;
  }
  const StretchDepths none{std::vector<double>(n, 0.0), std::vector<bool>(n, false)};
  if (middle < 0) return none;
  // Depths evenly spaced in inverse depth: the projection in a nearby view moves about evenly.
  const double q_lo = 1.0 / t_hi, q_hi = 1.0 / t_lo;
  double span_px = 0.0;
  for (size_t w = 0; w < views.size(); ++w) {
    if (static_cast<int>(w) == v) continue;
    const auto a = rig.cameras[w].Project(c + rays[middle] / q_lo);
    const auto b = rig.cameras[w].Project(c + rays[middle] / q_hi);
    if (a && b) span_px = std::max(span_px, (*a - *b).norm());
  }
  if (!(span_px > 0.0)) return none;
  const int depths =
      std::clamp(static_cast<int>(std::ceil(span_px / options.depth_step_px)) + 1, 2,
                 options.max_depths);
  const double dq = (q_hi - q_lo) / (depths - 1);
  const double cap2 = options.cap_px * options.cap_px;

  std::vector<double> unary(static_cast<size_t>(n) * depths, kExcluded);
  for (int i = 0; i < n; ++i) {
    if (!range[i]) continue;
    for (int k = 0; k < depths; ++k) {
      const double t = 1.0 / (q_lo + k * dq);
      if (t < range[i]->first || t > range[i]->second) continue;
      const Eigen::Vector3d p = c + t * rays[i];
      double cost = 0.0;
      int seen = 0;
      for (size_t w = 0; w < views.size(); ++w) {
        if (static_cast<int>(w) == v) continue;
        const auto uv = ProjectInside(rig.cameras[w], p, options.image_margin_px);
        if (!uv) {
          cost += options.missing_view_cost_px2;
          continue;
        }
        ++seen;
        const double d = CentrelineDistanceBilinear(views[w], *uv);
        cost += std::min(d * d, cap2);
      }
      if (seen > 0) unary[static_cast<size_t>(i) * depths + k] = cost;
    }
  }

  // Viterbi over (depth index k, step d = k_i - k_{i-1}).
  const int b = options.max_step, steps = 2 * b + 1;
  const size_t layer = static_cast<size_t>(depths) * steps;
  std::vector<double> prev(layer), cur(layer);
  std::vector<int8_t> back(static_cast<size_t>(n) * layer, 0);
  for (int k = 0; k < depths; ++k)
    for (int s = 0; s < steps; ++s) prev[static_cast<size_t>(k) * steps + s] = unary[k];
  for (int i = 1; i < n; ++i) {
    for (int k = 0; k < depths; ++k) {
      const double u = unary[static_cast<size_t>(i) * depths + k];
      for (int s = 0; s < steps; ++s) {
        const int from = k - (s - b);
        double best = std::numeric_limits<double>::infinity();
        int arg = b;
        if (from >= 0 && from < depths) {
          const double* row = &prev[static_cast<size_t>(from) * steps];
          for (int s0 = 0; s0 < steps; ++s0) {
            const double cost = row[s0] + options.smooth_px2 * (s - s0) * (s - s0);
            if (cost < best) {
              best = cost;
              arg = s0;
            }
          }
        }
        cur[static_cast<size_t>(k) * steps + s] = u + best;
        back[i * layer + static_cast<size_t>(k) * steps + s] = static_cast<int8_t>(arg);
      }
    }
    std::swap(prev, cur);
  }
  size_t arg = 0;
  for (size_t j = 1; j < layer; ++j)
    if (prev[j] < prev[arg]) arg = j;
  std::vector<int> path(n);
  int k = static_cast<int>(arg / steps), s = static_cast<int>(arg % steps);
  for (int i = n - 1; i >= 0; --i) {
    path[i] = k;
    if (i == 0) break;
    const int s0 = back[i * layer + static_cast<size_t>(k) * steps + s];
    k -= s - b;
    s = s0;
  }
  // Sub-step depth (a parabola through the costs either side), then a light smoothing.
  std::vector<double> q(n, 0.0);
  for (int i = 0; i < n; ++i) {
    const double* u = &unary[static_cast<size_t>(i) * depths];
    const int kk = path[i];
    double offset = 0.0;
    if (kk > 0 && kk + 1 < depths && u[kk] < kExcluded) {
      const double curvature = u[kk - 1] - 2 * u[kk] + u[kk + 1];
      if (curvature > 1e-9 && u[kk - 1] < kExcluded && u[kk + 1] < kExcluded)
        offset = std::clamp(0.5 * (u[kk - 1] - u[kk + 1]) / curvature, -0.5, 0.5);
    }
    q[i] = u[kk] < kExcluded ? q_lo + (kk + offset) * dq : 0.0;
  }
  StretchDepths out{std::vector<double>(n, 0.0), std::vector<bool>(n, false)};
  std::vector<double>& smoothed = out.q;
  const double consistent = options.accept_px * options.accept_px * (views.size() - 1);
  for (int i = 0; i < n; ++i) {
    const double* u = &unary[static_cast<size_t>(i) * depths];
    for (int kk = 0; kk < depths && !out.ambiguous[i]; ++kk) {
      out.ambiguous[i] = std::abs(kk - path[i]) > options.unique_exclusion_steps &&
                         u[kk] <= consistent;
    }
  }
  for (int i = 0; i < n; ++i) {
    if (q[i] == 0.0) continue;
    int r = 2;
    while (r > 0 && (i - r < 0 || i + r >= n)) --r;
    double sum = 0.0;
    int count = 0;
    for (int j = i - r; j <= i + r; ++j) {
      if (q[j] == 0.0) continue;
      sum += q[j];
      ++count;
    }
    smoothed[i] = sum / count;
  }
  return out;
}

}  // namespace vb::reconstruct::depth_sweep_internal
