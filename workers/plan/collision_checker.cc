// SPDX-License-Identifier: Apache-2.0
#include "workers/plan/collision_checker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace vb::plan {

void CollisionChecker::AreFree(std::span<const Joints> qs, std::span<bool> out) {
  for (size_t i = 0; i < qs.size() && i < out.size(); ++i) out[i] = IsFree(qs[i]);
}

int MotionSteps(const Joints& a, const Joints& b, double max_step_m, double reach_m) {
  constexpr int kMaxSteps = 1 << 20;
  // A point at distance r from a joint axis moves at most r |dq| when that joint turns by dq; the
  // motions of all joints add up along the chain, so sum_i |dq_i| * reach bounds every point.
  const double travel = (b - a).cwiseAbs().sum() * std::max(reach_m, 0.0);
  if (!std::isfinite(travel) || !(max_step_m > 0)) return kMaxSteps;
  const double steps = std::ceil(travel / max_step_m);
  return static_cast<int>(std::clamp(steps, 1.0, static_cast<double>(kMaxSteps)));
}

bool CollisionChecker::IsMotionFree(const Joints& a, const Joints& b, double max_step_m) {
  const int n = MotionSteps(a, b, max_step_m);
  // Ends first, then the interior in van der Corput order (coarse to fine) so that a colliding
  // motion usually fails after few checks; chunks let batched checkers work on many at once.
  std::array<bool, 2> ends_free{};
  const std::array<Joints, 2> ends = {a, b};
  AreFree(ends, ends_free);
  if (!ends_free[0] || !ends_free[1]) return false;
  if (n <= 1) return true;
  int bits = 0;
  while ((1 << bits) < n) ++bits;
  constexpr size_t kChunk = 16;
  std::vector<Joints> chunk;
  chunk.reserve(kChunk);
  std::array<bool, kChunk> free{};
  for (uint32_t i = 0; i < (1u << bits); ++i) {
    // Bit-reversed i, scaled into (0, n).
    uint32_t rev = 0;
    for (int k = 0; k < bits; ++k) rev |= ((i >> k) & 1u) << (bits - 1 - k);
    if (rev == 0 || static_cast<int>(rev) >= n) continue;
    chunk.push_back(a + (b - a) * (static_cast<double>(rev) / n));
    if (chunk.size() == kChunk || i + 1 == (1u << bits)) {
      AreFree(chunk, std::span<bool>(free.data(), chunk.size()));
      for (size_t k = 0; k < chunk.size(); ++k) {
        if (!free[k]) return false;
      }
      chunk.clear();
    }
  }
  if (!chunk.empty()) {
    AreFree(chunk, std::span<bool>(free.data(), chunk.size()));
    for (size_t k = 0; k < chunk.size(); ++k) {
      if (!free[k]) return false;
    }
  }
  return true;
}

}  // namespace vb::plan
